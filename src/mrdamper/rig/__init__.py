"""rig subpackage."""
