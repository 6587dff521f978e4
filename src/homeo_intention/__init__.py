"""homeo_intention package."""
