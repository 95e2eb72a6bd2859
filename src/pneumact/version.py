"""The package version (one place: the root package, the build and the reports read it)."""

__version__ = "0.2.0"
