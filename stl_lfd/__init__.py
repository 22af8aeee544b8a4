"""stlopt: adapt demonstrated robot skills to Signal Temporal Logic requirements."""

__version__ = "0.1.0"
