"""The version of mrdamper (its one source: the package metadata reads it from here)."""

__version__ = "0.2.0"
