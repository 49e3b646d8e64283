"""The ftkin version (one place: read by the package, the CLI, the calibration file and the
build).
"""

__version__ = "0.1.0"
