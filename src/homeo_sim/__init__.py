"""homeo_sim package."""
