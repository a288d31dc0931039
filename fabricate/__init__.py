"""Fabrication stages: offsets, solids, cut files, configs, pipeline and CLI."""
__version__ = "0.1.0"
