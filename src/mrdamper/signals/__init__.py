"""signals subpackage."""
