"""The vessel model: ship data, the MMG equations, actuators, environmental disturbances, manoeuvres."""
