"""COLREG machinery: encounter classification and rule scoring (numpy post-processing)."""
