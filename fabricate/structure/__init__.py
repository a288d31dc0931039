"""Structural check of the beam frame (OpenSees): sections, loads, model, solution, results, sizing.

Light to import: OpenSees and matplotlib are imported inside the functions that use them.
"""
from .options import CASES, DEFAULT_COMBINATIONS, GRADES, StructureOptions
from .sections import SHAPES, SectionProperties, i_section, plate, rhs, section, tee

__all__ = ["CASES", "DEFAULT_COMBINATIONS", "GRADES", "SHAPES", "SectionProperties", "StructureOptions",
           "i_section", "plate", "rhs", "section", "tee"]
