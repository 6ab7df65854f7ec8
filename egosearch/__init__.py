"""egosearch: a reproducible benchmark for learned egocentric object search."""

__version__ = "0.1.0"
