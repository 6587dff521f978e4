"""homeo_launch: the bringup package. The launchers (``homeo-launch sim | pepper | bench``, the field
test), node process management, benches and ``homeo-topic``; it imports any package, and no
package imports it."""
