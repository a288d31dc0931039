"""Glass build-ups: monolithic, laminated (plies and interlayers) and insulated (outer pane, cavity, inner pane).

A unit is a stack of layers along the panel normal, on the glass side of the
bearing face (the face that bears on the beams stays where a monolithic panel
has it).  Layers are listed from the outside (weather side, away from the
beams) to the inside (on the beams), the order a glazier writes a build-up
(``10/16/88.4``) and numbers the glass surfaces.

- every glass ply is one solid (``P0001.1``, ``P0001.2`` ...: ``k`` counts the
  solid layers from the outside);
- every **interlayer** (PVB, SGP) is a solid of its own too, between its two
  plies: it is part of the unit's thickness, weight (PVB 1070 kg/m3, SGP
  950 kg/m3) and of the 3D model (STEP, 3MF, IFC show a closed laminate), but
  it is not cut from glass sheet, so it has no glass cut file;
- the **cavity** of an insulated unit (argon, air, krypton) is no solid: its
  gas is in the build-up text and the IFC layer set; the spacer frame and the
  edge seal are made by the unit's fabricator and are not modelled: their
  width (``edge_seal_mm``, the spacer setback from the glass edge) is in the
  glass schedule, their weight is not in the unit weight;
- ``step_mm`` > 0 makes a stepped unit: the inner pane (and its spacer) is set
  back by that much from the outer pane's edge; the inner pane still bears on
  the beams, so the step must stay below the bearing width.

What a glass order needs besides the sizes (the vocabulary of EN 572-2, EN 1863-1,
EN 12150-1, EN 14179-1, EN ISO 12543, EN 1279 and DIN 1249-11, README "Glass order"):

- per ply its heat **treatment** (:data:`TREATMENTS`: ``float``, ``heat-strengthened``,
  ``toughened``, ``toughened-heat-soaked``) and its **edge work** (:data:`EDGES`:
  ``as-cut`` ... ``polished``, with the DIN 1249-11 code), given per pane as one word or a
  list of one per ply (``treatment``, ``edge_work``);
- the unit's **coatings** by glass surface, ``{2: low-E}`` (:data:`COATINGS`): surfaces
  are numbered from the outside, two per glass ply (``#1`` the weather face of the outer
  ply; an insulated ``10/16/66.2`` has ``#1`` to ``#6``);
- an insulated unit's **spacer** (:data:`SPACERS`) and its colour, its **secondary seal**
  (:data:`SEALS`) and the **gas fill** (% of the cavity, argon or krypton).

Left out, the defaults are those a facade engineer writes for an overhead roof: a
laminated pane of heat-strengthened plies (it holds together and stays in place when
broken), a monolithic pane toughened and heat-soaked (EN 14179: nickel sulphide
breakage screened), smooth ground edges, and for an insulated unit a selective
solar-control coating on ``#2``, a black warm-edge spacer, a silicone secondary seal
(UV-resistant) and 90 % gas.  :meth:`BuildUp.overhead_warnings` names the choices that
are unsafe over people (a monolithic lower pane: DIN 18008-2 asks laminated safety glass
there), and :func:`overhead_limit` the units they concern.

``layers()`` gives each layer's distance from the bearing face (``offset_mm``,
to its beam-side face), its thickness and its edge inset: the panels of
:mod:`fabricate.cad.panels` are built from exactly these numbers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from optimize.errors import ConfigError

INTERLAYER_DENSITY = {"PVB": 1070.0, "SGP": 950.0}
"""kg/m3 of the interlayers (PVB: polyvinyl butyral; SGP: SentryGlas ionoplast)."""
GASES = ("argon", "air", "krypton")
TYPES = ("monolithic", "laminated", "insulated")
PLY_MM = (2.0, 25.0)
"""Float glass is made from 2 to 25 mm thick."""
PVB_FILM_MM = 0.38
GLASS_THICKNESS = dict(gt=0.0, le=200.0)
"""Bounds of ``parts.glass_thickness``, the monolithic shorthand (mm)."""
BOUNDS = {"thickness_mm": dict(ge=PLY_MM[0], le=PLY_MM[1]), "interlayer_mm": dict(gt=0.0, le=10.0),
          "cavity_mm": dict(ge=4.0, le=50.0), "edge_seal_mm": dict(ge=5.0, le=50.0), "step_mm": dict(ge=0.0, le=200.0)}
"""Bounds of the ``parts.glass`` keys (mm): one place, which the config section reads too."""
GAS_FILL_PCT = dict(ge=0.0, le=100.0)
"""Bounds of ``parts.glass.gas_fill_pct``."""
TREATMENTS = {"float": ("annealed float glass", "EN 572-2"),
              "heat-strengthened": ("heat-strengthened glass (HSG, TVG)", "EN 1863-1"),
              "toughened": ("thermally toughened safety glass (FTG, ESG)", "EN 12150-1"),
              "toughened-heat-soaked": ("heat-soaked thermally toughened safety glass (ESG-H)", "EN 14179-1")}
"""Heat treatment of a ply: what it is, its product standard."""
EDGES = {"as-cut": ("KG", "cut edge, not worked"),
         "arrissed": ("KGS", "arrissed (seamed): the sharp arrises chamfered"),
         "ground": ("KMG", "ground to size, blank spots allowed"),
         "smooth-ground": ("KGN", "smooth ground all over, matt"),
         "polished": ("KPO", "polished, glossy")}
"""Edge work of a ply (EN 12150-1 / EN 1863-1 terms) and its DIN 1249-11 code."""
COATINGS = ("low-E", "solar-control", "self-cleaning", "anti-reflective", "enamel")
"""Coatings a surface may carry (``solar-control``: a selective coating, low emissivity too)."""
SPACERS = ("warm-edge", "aluminium", "stainless-steel", "TPS")
"""Spacer of an insulated unit (TPS: thermoplastic spacer extruded onto the glass)."""
SEALS = ("silicone", "polysulphide", "polyurethane")
"""Secondary (outer) edge seal of an insulated unit: silicone where it sees UV (a stepped or exposed edge)."""
COLOUR_CHARS = 40
"""Longest spacer colour text."""
WORKED_BEFORE = ("heat-strengthened", "toughened", "toughened-heat-soaked")
"""Treatments whose edges must be worked (at least arrissed) before the furnace (EN 1863-1, EN 12150-1)."""
OVERHEAD_DEG = 10.0
"""A unit inclined more than this from the vertical is overhead glazing (DIN 18008-1)."""
LAMINATED_STANDARD = "EN ISO 12543-2"
INSULATED_STANDARD = "EN 1279-5"


def _number(key: str, value, bounds: dict, unit: str = "mm") -> float:
    """``value`` as a float within ``bounds`` (``ge`` or ``gt``, and ``le``), else ConfigError naming ``key``."""
    lo, hi, low_open = bounds.get("ge", bounds.get("gt")), bounds["le"], "gt" in bounds
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value > hi or value < lo or (low_open and value <= lo):
        rng = f"({lo:g}, {hi:g}]" if low_open else f"[{lo:g}, {hi:g}]"
        raise ConfigError(f"{key} = {value!r}: expected a number in {rng} {unit}")
    return float(value)


@dataclass(frozen=True)
class Layer:
    """One layer of a unit: a solid (glass ply, interlayer) or the cavity.

    member : its name in the unit (``"ply 1"``, ``"interlayer 1"``, ``"outer pane"``, ``"cavity"``).
    material : ``glass`` | ``PVB`` | ``SGP`` | the cavity's gas.
    thickness_mm : along the panel normal.  offset_mm : from the bearing face (on the beams), away from
    the beams, to the layer's beam-side face.  inset_mm : its edges set back from the unit's edge.
    solid : a solid of the model (every layer but the cavity).
    """

    member: str
    material: str
    thickness_mm: float
    offset_mm: float
    inset_mm: float
    solid: bool


def default_treatment(n_plies: int) -> str:
    """The overhead default of a pane of ``n_plies``: a laminated pane of heat-strengthened plies (it stays
    in place when broken), a monolithic one toughened and heat-soaked (EN 14179-1)."""
    return "heat-strengthened" if n_plies > 1 else "toughened-heat-soaked"


@dataclass(frozen=True)
class Pane:
    """A monolithic pane (one ply) or a laminated one (plies with one interlayer between each two)."""

    plies_mm: tuple[float, ...]
    interlayer: str = "PVB"
    interlayer_mm: float = 0.0
    treatment: tuple[str, ...] = ()
    """per ply (:data:`TREATMENTS`); not given: the overhead default (:func:`default_treatment`)."""
    edge: tuple[str, ...] = ()
    """per ply (:data:`EDGES`); not given: smooth-ground."""

    def __post_init__(self):
        n = len(self.plies_mm)
        if not self.treatment:
            object.__setattr__(self, "treatment", (default_treatment(n),) * n)
        if not self.edge:
            object.__setattr__(self, "edge", ("smooth-ground",) * n)

    @property
    def laminated(self) -> bool:
        return len(self.plies_mm) > 1

    @property
    def thickness_mm(self) -> float:
        return sum(self.plies_mm) + (len(self.plies_mm) - 1) * self.interlayer_mm

    def short(self) -> str:
        """The supplier's notation: ``10``; laminated PVB of plies under 10 mm in 0.38 mm films:
        ``88.4`` (8 + 8, four films = 1.52 mm); otherwise ``8 + 1.52 SGP + 8``."""
        if not self.laminated:
            return f"{self.plies_mm[0]:g}"
        films = self.interlayer_mm / PVB_FILM_MM
        if (self.interlayer == "PVB" and len(self.plies_mm) == 2 and all(p < 10 and p == int(p) for p in self.plies_mm)
                and abs(films - round(films)) < 1e-9):
            return f"{int(self.plies_mm[0])}{int(self.plies_mm[1])}.{int(round(films))}"
        return self.long()

    def long(self) -> str:
        """``8 + 1.52 PVB + 8`` (every ply and interlayer, mm)."""
        if not self.laminated:
            return f"{self.plies_mm[0]:g}"
        join = f" + {self.interlayer_mm:g} {self.interlayer} + "
        return join.join(f"{p:g}" for p in self.plies_mm)

    def layers(self, prefix: str) -> list[tuple[str, str, float]]:
        """``[(member, material, thickness)]`` from the outside in."""
        if not self.laminated:
            return [((prefix + " pane").strip() if prefix else "ply 1", "glass", self.plies_mm[0])]
        out = []
        head = f"{prefix} " if prefix else ""
        for j, p in enumerate(self.plies_mm):
            if j:
                out.append((f"{head}interlayer {j}", self.interlayer, self.interlayer_mm))
            out.append((f"{head}ply {j + 1}", "glass", p))
        return out


@dataclass(frozen=True)
class BuildUp:
    """A glass unit: ``type`` monolithic | laminated (``outer`` is the pane) | insulated (``outer`` pane,
    ``cavity_mm`` of ``gas``, ``inner`` pane on the beams, spacer ``edge_seal_mm`` in from the edge,
    inner pane ``step_mm`` in from the outer pane's edge)."""

    type: str
    outer: Pane
    inner: Pane | None = None
    cavity_mm: float = 0.0
    gas: str = ""
    edge_seal_mm: float = 0.0
    step_mm: float = 0.0
    coatings: tuple[tuple[int, str], ...] = ()
    """``(surface, coating)`` pairs, surfaces numbered from the outside (two per glass ply)."""
    spacer: str = ""
    spacer_colour: str = ""
    secondary_seal: str = ""
    gas_fill_pct: float = 0.0

    @classmethod
    def monolithic(cls, thickness_mm: float) -> "BuildUp":
        return cls("monolithic", Pane((float(thickness_mm),)))

    @classmethod
    def from_config(cls, data: dict | None, glass_thickness: float = 10.0, key: str = "parts.glass") -> "BuildUp":
        """The build-up of a ``parts.glass`` mapping (None: monolithic ``glass_thickness``).

        Raises ConfigError naming the key for an unknown type, a missing or misplaced key, or a
        thickness out of range."""
        if data is None:
            return cls.monolithic(_number("parts.glass_thickness", glass_thickness, GLASS_THICKNESS))
        if isinstance(data, BuildUp):
            return data
        if not isinstance(data, dict):
            raise ConfigError(f"{key} = {data!r}: expected a mapping with type monolithic | laminated | insulated")
        data = {k: v for k, v in data.items() if v is not None}
        kind = data.get("type")
        if kind not in TYPES:
            raise ConfigError(f"{key}.type = {kind!r}: expected one of {', '.join(TYPES)}")
        if kind != "insulated":
            extra = sorted(set(data) & {"outer", "inner", "cavity_mm", "gas", "edge_seal_mm", "step_mm", *IGU_KEYS})
            if extra:
                raise ConfigError(f"{key}.{extra[0]}: applies to an insulated unit, not to type {kind}")
            unit = cls(kind, _pane(data, key, kind))
            return unit.with_coatings(_coatings(data.get("coatings"), key, unit.n_plies))
        extra = sorted(set(data) & {"thickness_mm", "plies_mm", "interlayer", "interlayer_mm", "treatment",
                                    "edge_work"})
        if extra:
            raise ConfigError(f"{key}.{extra[0]}: an insulated unit takes its panes as {key}.outer and "
                              f"{key}.inner (each monolithic or laminated)")
        panes = {}
        for side in ("outer", "inner"):
            p = data.get(side)
            if not isinstance(p, dict):
                raise ConfigError(f"{key}.{side} = {p!r}: expected a pane, e.g. {{type: monolithic, "
                                  "thickness_mm: 8}} or {type: laminated, plies_mm: [8, 8], interlayer_mm: 1.52}")
            pk = {k: v for k, v in p.items() if v is not None}
            ptype = pk.get("type", "monolithic")
            if ptype not in ("monolithic", "laminated"):
                raise ConfigError(f"{key}.{side}.type = {ptype!r}: expected monolithic or laminated")
            panes[side] = _pane(pk, f"{key}.{side}", ptype)
        gas = data.get("gas", "argon")
        if gas not in GASES:
            raise ConfigError(f"{key}.gas = {gas!r}: expected one of {', '.join(GASES)}")
        unit = cls("insulated", panes["outer"], panes["inner"],
                   cavity_mm=_number(f"{key}.cavity_mm", data.get("cavity_mm", 16.0), BOUNDS["cavity_mm"]),
                   gas=gas, edge_seal_mm=_number(f"{key}.edge_seal_mm", data.get("edge_seal_mm", 16.0),
                                                      BOUNDS["edge_seal_mm"]),
                   step_mm=_number(f"{key}.step_mm", data.get("step_mm", 0.0), BOUNDS["step_mm"]),
                   spacer=_word(f"{key}.spacer", data.get("spacer", "warm-edge"), SPACERS),
                   spacer_colour=_colour(f"{key}.spacer_colour", data.get("spacer_colour", "black")),
                   secondary_seal=_word(f"{key}.secondary_seal", data.get("secondary_seal", "silicone"), SEALS),
                   gas_fill_pct=0.0 if gas == "air" else _number(f"{key}.gas_fill_pct", data.get("gas_fill_pct", 90.0),
                                                                 GAS_FILL_PCT, unit="%"))
        return unit.with_coatings(_coatings(data.get("coatings", {2: "solar-control"}), key, unit.n_plies))

    @property
    def thickness_mm(self) -> float:
        """The whole unit, cavity included."""
        inner = self.inner.thickness_mm + self.cavity_mm if self.inner is not None else 0.0
        return self.outer.thickness_mm + inner

    def layers(self) -> tuple[Layer, ...]:
        """Every layer from the outside (away from the beams) to the inside (on the beams)."""
        rows: list[tuple[str, str, float, float]] = []           # member, material, thickness, inset
        if self.inner is None:
            rows += [(m, mat, t, 0.0) for m, mat, t in self.outer.layers("")]
        else:
            rows += [(m, mat, t, 0.0) for m, mat, t in self.outer.layers("outer")]
            rows.append(("cavity", self.gas, self.cavity_mm, self.step_mm))
            rows += [(m, mat, t, self.step_mm) for m, mat, t in self.inner.layers("inner")]
        out, below = [], 0.0
        for member, material, t, inset in reversed(rows):  # offsets summed from the bearing face up
            out.append(Layer(member, material, float(t), below, float(inset), member != "cavity"))
            below += t
        return tuple(reversed(out))

    def solids(self) -> tuple[Layer, ...]:
        """The solid layers (plies and interlayers), outside in: solid ``k`` (from 1) is ``<unit>.<k>``."""
        return tuple(layer for layer in self.layers() if layer.solid)

    def glass_mm(self) -> float:
        """The glass in the unit (mm), interlayers and cavity not counted."""
        return sum(layer.thickness_mm for layer in self.layers() if layer.material == "glass")

    def weight_thickness_mm(self, density_glass: float) -> float:
        """mm of glass of ``density_glass`` that weighs what the unit's plies and interlayers weigh per m2."""
        return sum(layer.thickness_mm * (1.0 if layer.material == "glass" else INTERLAYER_DENSITY[layer.material]
                                         / density_glass) for layer in self.solids())

    def density(self, material: str, density_glass: float) -> float:
        """kg/m3 of a layer's material."""
        return INTERLAYER_DENSITY.get(material, density_glass)

    def short(self) -> str:
        """``10``, ``88.4``, ``10/16/88.4``: the build-up as a supplier writes it (outside first, mm)."""
        if self.inner is None:
            return self.outer.short()
        return f"{self.outer.short()}/{self.cavity_mm:g}/{self.inner.short()}"

    def describe(self) -> str:
        """The build-up spelled out: ``insulated 10/16/88.4 (10 | 16 argon | 8 + 1.52 PVB + 8)``."""
        if self.type == "monolithic":
            return f"monolithic {self.outer.short()} mm"
        if self.type == "laminated":
            return f"laminated {self.outer.short()} ({self.outer.long()})"
        step = f", inner pane stepped {self.step_mm:g}" if self.step_mm else ""
        return (f"insulated {self.short()} ({self.outer.long()} | {self.cavity_mm:g} {self.gas} | "
                f"{self.inner.long()}; edge seal {self.edge_seal_mm:g}{step})")

    def check_bearing(self, bearing_mm: float) -> None:
        """Raise ConfigError when a stepped inner pane would not reach the beams (``bearing_mm``: the
        width each panel edge bears on, ``(beam_width - joint_gap) / 2``)."""
        if self.step_mm and self.step_mm >= bearing_mm:
            raise ConfigError(f"parts.glass.step_mm = {self.step_mm:g} mm: the inner pane would not bear on the "
                              f"beams (bearing width (parts.beam_width - parts.joint_gap) / 2 = {bearing_mm:g} mm); "
                              "expected a smaller step or wider beams")

    def as_config(self) -> dict:
        """The ``parts.glass`` mapping of this build-up."""
        def pane(p: Pane) -> dict:
            work = {"treatment": list(p.treatment), "edge_work": list(p.edge)}
            if not p.laminated:
                return {"type": "monolithic", "thickness_mm": p.plies_mm[0], **work}
            return {"type": "laminated", "plies_mm": list(p.plies_mm), "interlayer": p.interlayer,
                    "interlayer_mm": p.interlayer_mm, **work}
        coatings = {"coatings": {s: c for s, c in self.coatings}}
        if self.inner is None:
            return {**pane(self.outer), **coatings}
        return {"type": "insulated", "outer": pane(self.outer), "cavity_mm": self.cavity_mm, "gas": self.gas,
                "inner": pane(self.inner),
                "edge_seal_mm": self.edge_seal_mm, "step_mm": self.step_mm, **coatings, "spacer": self.spacer,
                "spacer_colour": self.spacer_colour, "secondary_seal": self.secondary_seal,
                "gas_fill_pct": self.gas_fill_pct}

    # -- what a glass order names besides sizes ------------------------------------------------------
    @property
    def n_plies(self) -> int:
        """Glass plies in the unit."""
        return len(self.outer.plies_mm) + (len(self.inner.plies_mm) if self.inner is not None else 0)

    def with_coatings(self, coatings: tuple[tuple[int, str], ...]) -> "BuildUp":
        from dataclasses import replace

        return replace(self, coatings=coatings)

    def plies(self) -> tuple["Ply", ...]:
        """Every glass ply outside in with its thickness, treatment, edge work, surfaces and coatings."""
        out = []
        panes = [("outer", self.outer)] + ([("inner", self.inner)] if self.inner is not None else [])
        coat = dict(self.coatings)
        for side, p in panes:  # one or two panes
            for t, treat, edge in zip(p.plies_mm, p.treatment, p.edge):
                k = len(out) + 1
                surfaces = (2 * k - 1, 2 * k)
                out.append(Ply(k, side if self.inner is not None else "", t, treat, edge, surfaces,
                               tuple((s, coat[s]) for s in surfaces if s in coat)))
        return tuple(out)

    def lower_pane(self) -> Pane:
        """The pane over people: the inner one of an insulated unit, else the unit."""
        return self.inner if self.inner is not None else self.outer

    def overhead_warnings(self) -> list[str]:
        """Why this build-up is unsafe or weak as overhead glazing (empty: none)."""
        out = []
        low = self.lower_pane()
        side = "inner pane" if self.inner is not None else "pane"
        kind = self.plies()[-1].treatment
        if not low.laminated:
            out.append(f"a monolithic {kind} {side} overhead falls when it breaks (toughened glass in small "
                       "pieces, others in shards): DIN 18008-2 asks laminated safety glass for the lower pane "
                       "of overhead glazing")
        else:
            if set(low.treatment) <= {"toughened", "toughened-heat-soaked"}:
                out.append(f"the laminated {side} is toughened in every ply: when all its plies break it has "
                           "little residual strength and may sag out of its supports (heat-strengthened or "
                           "float plies stay in place)")
        return out

    def standards(self) -> list[str]:
        """The product standards of the unit and its plies."""
        out = sorted({TREATMENTS[p.treatment][1] for p in self.plies()})
        if self.outer.laminated or (self.inner is not None and self.inner.laminated):
            out.append(LAMINATED_STANDARD)
        if self.inner is not None:
            out.append(INSULATED_STANDARD)
        return out


@dataclass(frozen=True)
class Ply:
    """One glass ply of a unit for the glass order: ``k`` from 1 outside in, the ``pane`` it belongs to
    (``outer`` / ``inner`` of an insulated unit, else empty), thickness, treatment, edge work, its two
    surface numbers and the coatings on them."""

    k: int
    pane: str
    thickness_mm: float
    treatment: str
    edge: str
    surfaces: tuple[int, int]
    coatings: tuple[tuple[int, str], ...]

    def describe(self) -> str:
        """``8 mm heat-strengthened, edge smooth-ground (KGN), #2 low-E``."""
        coat = "".join(f", #{s} {c}" for s, c in self.coatings)
        return f"{self.thickness_mm:g} mm {self.treatment}, edge {self.edge} ({EDGES[self.edge][0]}){coat}"


IGU_KEYS = ("spacer", "spacer_colour", "secondary_seal", "gas_fill_pct")
"""Keys of an insulated unit only."""


def _word(key: str, value, allowed) -> str:
    if value not in allowed:
        raise ConfigError(f"{key} = {value!r}: expected one of {', '.join(allowed)}")
    return value


def _colour(key: str, value) -> str:
    if not isinstance(value, str) or not value.strip() or len(value) > COLOUR_CHARS or not value.isprintable():
        raise ConfigError(f"{key} = {value!r}: expected a colour name of 1 to {COLOUR_CHARS} printable characters")
    return value.strip()


def _per_ply(key: str, value, n: int, allowed) -> tuple[str, ...]:
    """One word for every ply, or a list of one per ply; () when not given."""
    if value is None:
        return ()
    words = list(value) if isinstance(value, (list, tuple)) else [value] * n
    if len(words) != n:
        raise ConfigError(f"{key} = {value!r}: expected one word or a list of {n} (one per ply)")
    return tuple(_word(f"{key}[{j}]" if isinstance(value, (list, tuple)) else key, w, allowed)
                 for j, w in enumerate(words))


def _coatings(value, key: str, n_plies: int) -> tuple[tuple[int, str], ...]:
    """``{surface: coating}`` as sorted pairs; surfaces 1 .. 2 n_plies."""
    if value is None:
        return ()
    if not isinstance(value, dict):
        raise ConfigError(f"{key}.coatings = {value!r}: expected a mapping of surface number to coating, "
                          "e.g. {2: low-E}")
    out = []
    for s, c in value.items():
        num = int(s.removeprefix("#")) if isinstance(s, str) and s.removeprefix("#").isdigit() else s
        if isinstance(num, bool) or not isinstance(num, int) or not 1 <= num <= 2 * n_plies:
            raise ConfigError(f"{key}.coatings: surface {s!r}: expected a glass surface 1 .. {2 * n_plies} "
                              f"(two per ply, #1 the weather face)")
        out.append((num, _word(f"{key}.coatings.{num}", c, COATINGS)))
    return tuple(sorted(out))


def _worked(key: str, treatment: tuple[str, ...], edge: tuple[str, ...]) -> None:
    for j, (t, e) in enumerate(zip(treatment, edge)):
        if e == "as-cut" and t in WORKED_BEFORE:
            raise ConfigError(f"{key}.edge_work = as-cut on a {t} ply (ply {j + 1}): its edges are worked before "
                              "the furnace (EN 12150-1, EN 1863-1); expected arrissed, ground, smooth-ground or "
                              "polished")


def _pane(data: dict, key: str, kind: str) -> Pane:
    pane = _pane_sizes(data, key, kind)
    n = len(pane.plies_mm)
    treat = _per_ply(f"{key}.treatment", data.get("treatment"), n, tuple(TREATMENTS))
    edge = _per_ply(f"{key}.edge_work", data.get("edge_work"), n, tuple(EDGES))
    from dataclasses import replace

    pane = replace(pane, treatment=treat, edge=edge)
    _worked(key, pane.treatment, pane.edge)
    return pane


def _pane_sizes(data: dict, key: str, kind: str) -> Pane:
    if kind == "monolithic":
        for bad in ("plies_mm", "interlayer", "interlayer_mm"):
            if bad in data:
                raise ConfigError(f"{key}.{bad}: applies to a laminated pane, not to type monolithic "
                                  f"(give {key}.thickness_mm)")
        if "thickness_mm" not in data:
            raise ConfigError(f"{key}.thickness_mm: missing; a monolithic pane needs its thickness (mm)")
        return Pane((_number(f"{key}.thickness_mm", data["thickness_mm"], BOUNDS["thickness_mm"]),))
    if "thickness_mm" in data:
        raise ConfigError(f"{key}.thickness_mm: a laminated pane is given by {key}.plies_mm (and its interlayer), "
                          "not by one thickness")
    plies = data.get("plies_mm")
    if not isinstance(plies, (list, tuple)) or len(plies) < 2:
        raise ConfigError(f"{key}.plies_mm = {plies!r}: expected a list of two or more ply thicknesses (mm), "
                          "e.g. [8, 8]")
    plies = tuple(_number(f"{key}.plies_mm[{j}]", p, BOUNDS["thickness_mm"]) for j, p in enumerate(plies))
    inter = data.get("interlayer", "PVB")
    if inter not in INTERLAYER_DENSITY:
        raise ConfigError(f"{key}.interlayer = {inter!r}: expected one of {', '.join(INTERLAYER_DENSITY)}")
    t = _number(f"{key}.interlayer_mm", data.get("interlayer_mm", 1.52), BOUNDS["interlayer_mm"])
    return Pane(plies, inter, t)


def bearing_groups(parts) -> list:
    """The panel groups of the ply on the beams (every panel group of a monolithic build-up): one
    solid per unit, which the glass schedule, the layout plan and the shop limits describe."""
    solids = parts.spec.glass.solids() if hasattr(parts.spec, "glass") else ()
    last = solids[-1].member if len(solids) > 1 else ""
    return [g for g in parts.of_kind("panel") if g.member == last]


def unit_sums(parts, values) -> np.ndarray:
    """(n_faces,) per mesh face the sum over every panel solid of ``values(group) (p,)``."""
    n = 1 + max((int(g.element.max()) for g in parts.of_kind("panel") if len(g)), default=-1)
    out = np.zeros(n)
    for g in parts.of_kind("panel"):  # a few groups (layers x face sizes)
        np.add.at(out, g.element, values(g))
    return out


def unit_blank(parts) -> np.ndarray:
    """(n_faces, 2) per mesh face the blank of its glass unit: width >= height of a rectangle that holds
    every glass ply of the unit, each in its own stock orientation (``PartGroup.rect``): the largest
    width and the largest height over the plies (the ply of the largest area may be the narrower one:
    a stepped or bevelled unit's plies differ in both directions)."""
    n = 1 + max((int(g.element.max()) for g in parts.of_kind("panel") if len(g)), default=-1)
    out = np.zeros((n, 2))
    for g in parts.of_kind("panel"):  # a few groups (plies x face sizes)
        if not g.material:
            np.maximum.at(out, g.element, g.rect)
    return out


def overhead_limit(groups, spec) -> dict:
    """``{"overhead": entry}`` in the form of the shop limits (:func:`fabricate.cad.limits.check_limits`):
    the glass units inclined more than :data:`OVERHEAD_DEG` from the vertical (overhead glazing) whose
    build-up :meth:`BuildUp.overhead_warnings` finds unsafe there, by unit id; ``worst`` the steepest
    inclination (degrees from vertical).  Empty for a build-up with no such warning."""
    build_up = getattr(spec, "glass", None)
    if build_up is None or not build_up.overhead_warnings():
        return {}
    solids = build_up.solids()
    last = solids[-1].member if len(solids) > 1 else ""
    ids, tilt = [], []
    for g in groups:  # the bearing ply of every unit, a few groups
        if g.kind != "panel" or g.member != last or not len(g):
            continue
        n_z = np.abs(g.normals[:, g.outline_face, 2])
        deg = np.degrees(np.arcsin(np.clip(n_z, 0.0, 1.0)))       # from the vertical
        over = deg > OVERHEAD_DEG
        ids += [i.split(".", 1)[0] for i in np.asarray(g.ids)[over]]
        tilt += deg[over].tolist()
    entry = {"limit": f"a laminated lower pane, not toughened in every ply, where over {OVERHEAD_DEG:g} deg from "
                      "vertical (DIN 18008-2)",
             "count": len(ids), "ids": ids, "why": "; ".join(build_up.overhead_warnings())}
    if ids:
        j = int(np.argmax(tilt))
        entry.update(worst=round(float(tilt[j]), 2), worst_id=ids[j])
    return {"overhead": entry}
