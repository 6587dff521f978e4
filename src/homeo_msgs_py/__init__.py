"""homeo_msgs_py package."""
