"""A DSTV NC1 reader, written from the DSTV description apart from the writer
(:mod:`fabricate.export.nc1`; the two share no code), used by ``fabricate check`` and the tests.

Blocks start with a two-letter keyword alone at the start of a line; ``ST`` holds 24 header lines
after optional ``**`` comments; ``AK`` lines are ``[face] x y radius ...``, the face flag present on
a contour's first line (and wherever the face changes).  Raises ValueError naming the file and what
is wrong."""
from __future__ import annotations

import os
import re

import numpy as np

HEADER = ("order", "drawing", "phase", "piece", "grade", "quantity", "profile", "code", "length",
          "height", "flange_width", "flange_thickness", "web_thickness", "radius", "weight_per_m",
          "paint_per_m", "web_start_cut", "web_end_cut", "flange_start_cut", "flange_end_cut",
          "text1", "text2", "text3", "text4")
NUMERIC = HEADER[8:20]
FACES = {"v", "o", "u", "h"}
KEYWORD = re.compile(r"^([A-Z]{2})[^\S\n]*$", re.MULTILINE)
"""A block keyword line of the lines joined by ``\n``: two capitals, then white space only."""
COMMENT = re.compile(r"^\*\*.*\n", re.MULTILINE)
"""A comment line (and its line end) of the lines joined by ``\n``."""


def read_nc1(path) -> dict:
    """``{"header": {field: value}, "contours": [(face, (k, 2) points)], "blocks": [names]}``.

    The lines are the text's (any line end of ``str.splitlines``), ``**`` comment lines dropped; the
    comments and the block keywords are found by regular expressions over all the lines joined by
    ``\n`` (:data:`COMMENT`, :data:`KEYWORD`: two capitals and white space alone on a line)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_BINARY", 0))
    try:
        data = os.read(fd, 1 << 16)
        while chunk := os.read(fd, 1 << 20):
            data += chunk
    finally:
        os.close(fd)
    text = "\n".join(data.decode("ascii").splitlines()) + "\n"     # every line ends in "\n"
    if "**" in text:
        text = COMMENT.sub("", text)
    first, *rest = KEYWORD.split(text)                              # [before, name, body, name, body ...]
    if first.strip():
        raw = next(raw for raw in first.split("\n") if raw.strip())
        raise ValueError(f"{path}: data before the first block: {raw!r}")
    names = rest[0::2]
    bodies = [body[1:].split("\n")[:-1] for body in rest[1::2]]  # a body: "\n" and its lines, each + "\n"
    if names[:1] != ["ST"] or names[-1:] != ["EN"]:
        raise ValueError(f"{path}: expected ST ... EN, found {names}")
    st = bodies[0]
    if len(st) < len(HEADER):
        raise ValueError(f"{path}: ST has {len(st)} lines, expected {len(HEADER)}")
    header = dict(zip(HEADER, map(str.strip, st)))
    header.update(zip(NUMERIC, map(float, [header[k] for k in NUMERIC])))
    header["quantity"] = int(header["quantity"])
    contours = []
    for name, body in zip(names, bodies):
        if name != "AK":
            continue
        face, pts = None, []
        for line in body:
            tokens = line.split()
            if not tokens:
                continue
            if tokens[0] in FACES:
                face, tokens = tokens[0], tokens[1:]
            x = float(tokens[0].rstrip("uosr")) if tokens else None
            if len(tokens) < 2:
                raise ValueError(f"{path}: AK line {line!r}: expected x y")
            pts.append([x, float(tokens[1])])
        contours.append((face, np.array(pts)))
    return {"header": header, "contours": contours, "blocks": names}
