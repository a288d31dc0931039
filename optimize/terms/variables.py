"""Named slices of the unknown vector.

The optimizer's unknown ``x`` stacks blocks such as ``vertices (n, 3)``,
``normals (m, 3)``, ``axes (p, 3)``, ``cos (p,)``; constraints and energies
ask the layout for a block by name and never do offset arithmetic.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class Layout:
    """Blocks of the unknown vector, in order: ``name -> (count, width)``."""

    blocks: dict[str, tuple[int, int]] = field(default_factory=dict)

    def add(self, name: str, count: int, width: int) -> Layout:
        """Append a block of ``count`` items of ``width`` scalars; returns self."""
        if name in self.blocks:
            raise ValueError(f"Layout: block {name!r} already exists")
        self.blocks[name] = (int(count), int(width))
        return self

    @classmethod
    def vertices_only(cls, n: int) -> Layout:
        """The unknowns ``vertices (n, 3)`` alone: ``x = V.ravel()`` (the paper's methods)."""
        return cls().add("vertices", n, 3)

    @property
    def size(self) -> int:
        """Length of the unknown vector."""
        return sum(c * w for c, w in self.blocks.values())

    def offset(self, name: str) -> int:
        """First index of block ``name``."""
        start = 0
        for key, (c, w) in self.blocks.items():
            if key == name:
                return start
            start += c * w
        raise KeyError(f"Layout: no block {name!r}; blocks are {list(self.blocks)}")

    def slice(self, name: str) -> slice:
        start = self.offset(name)
        c, w = self.blocks[name]
        return slice(start, start + c * w)

    def index(self, name: str) -> np.ndarray:
        """(count, width) int: global indices of the block's scalars (``(count,)`` when width 1)."""
        c, w = self.blocks[name]
        idx = self.offset(name) + np.arange(c * w).reshape(c, w)
        return idx[:, 0] if w == 1 else idx

    def view(self, x: np.ndarray, name: str) -> np.ndarray:
        """Block ``name`` of ``x`` as ``(count, width)`` (``(count,)`` when width 1); a view."""
        c, w = self.blocks[name]
        v = x[self.slice(name)]
        return v if w == 1 else v.reshape(c, w)

    def __contains__(self, name: str) -> bool:
        return name in self.blocks

    def pack(self, **arrays: np.ndarray) -> np.ndarray:
        """The stacked vector from one array per block (every block required)."""
        missing = set(self.blocks) - set(arrays)
        if missing:
            raise ValueError(f"Layout.pack: missing blocks {sorted(missing)}")
        x = np.empty(self.size)
        for name, (c, w) in self.blocks.items():
            a = np.asarray(arrays[name], dtype=np.float64)
            if a.size != c * w:
                raise ValueError(f"Layout.pack: block {name!r} has {a.size} values, expected {c} x {w}")
            x[self.slice(name)] = a.ravel()
        return x
