"""devsim – software twins of legacy motion controllers on virtual serial ports."""

__version__ = "0.1.0"
