"""study subpackage."""
