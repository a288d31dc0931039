"""Fabrication: the stages (offset, cad, export, structure, report) and the application layer
(``fabricate.app``: options, config, records, stages, pipeline, batch, CLI)."""
__version__ = "0.1.0"
