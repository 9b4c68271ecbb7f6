"""COLREG machinery: geometry, encounter classification, rule scoring, pair assessment (numpy post-processing)."""
