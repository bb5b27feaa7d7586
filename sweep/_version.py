"""The package version (read by the build backend and by `sweep.io` for attributes)."""

__version__ = "0.3.0.dev3"
