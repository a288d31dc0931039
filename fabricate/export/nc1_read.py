"""A DSTV NC1 reader, written from the DSTV description apart from the writer
(:mod:`fabricate.export.nc1`; the two share no code), used by ``fabricate check`` and the tests.

Blocks start with a two-letter keyword alone at the start of a line; ``ST`` holds 24 header lines
after optional ``**`` comments; ``AK`` lines are ``[face] x y radius ...``, the face flag present on
a contour's first line (and wherever the face changes).  Raises ValueError naming the file and what
is wrong."""
from __future__ import annotations

import numpy as np

HEADER = ("order", "drawing", "phase", "piece", "grade", "quantity", "profile", "code", "length",
          "height", "flange_width", "flange_thickness", "web_thickness", "radius", "weight_per_m",
          "paint_per_m", "web_start_cut", "web_end_cut", "flange_start_cut", "flange_end_cut",
          "text1", "text2", "text3", "text4")
NUMERIC = HEADER[8:20]
FACES = {"v", "o", "u", "h"}


def read_nc1(path) -> dict:
    """``{"header": {field: value}, "contours": [(face, (k, 2) points)], "blocks": [names]}``."""
    blocks: list[tuple[str, list[str]]] = []
    for raw in open(path, encoding="ascii", newline="").read().splitlines():
        if raw.startswith("**"):
            continue
        if len(raw) >= 2 and raw[:2].isalpha() and raw[:2].isupper() and raw[2:].strip() == "":
            blocks.append((raw[:2], []))
        elif blocks:
            blocks[-1][1].append(raw)
        elif raw.strip():
            raise ValueError(f"{path}: data before the first block: {raw!r}")
    names = [b for b, _ in blocks]
    if names[:1] != ["ST"] or names[-1:] != ["EN"]:
        raise ValueError(f"{path}: expected ST ... EN, found {names}")
    st = blocks[0][1]
    if len(st) < len(HEADER):
        raise ValueError(f"{path}: ST has {len(st)} lines, expected {len(HEADER)}")
    header = {k: v.strip() for k, v in zip(HEADER, st)}
    for k in NUMERIC:
        header[k] = float(header[k])
    header["quantity"] = int(header["quantity"])
    contours = []
    for name, lines in blocks:
        if name != "AK":
            continue
        face, pts = None, []
        for line in lines:
            tokens = line.split()
            if not tokens:
                continue
            if tokens[0] in FACES:
                face, tokens = tokens[0], tokens[1:]
            pts.append([float(tokens[0].rstrip("uosr")), float(tokens[1])])
        contours.append((face, np.array(pts)))
    return {"header": header, "contours": contours, "blocks": names}
