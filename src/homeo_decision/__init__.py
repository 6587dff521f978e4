"""homeo_decision package."""
