"""pepper_bridge package."""
