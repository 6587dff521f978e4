"""homeo_rover: a small deterministic rover as a world of homeo-robot (the world is ``homeo_rover.world.RoverWorld``)."""
