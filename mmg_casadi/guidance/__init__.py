"""Guidance methods: ILOS and PD heading control, potential fields, the velocity obstacle, colregs-vortex, the registry."""
