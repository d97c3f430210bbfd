"""The package version, apart so that the result writers can record it without importing the
public API above them."""
__version__ = "0.1.0"
