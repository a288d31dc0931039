"""Stock bars (cutting plan, bar order, the cut list's bar, the check from the files) and the glazing
gasket's fold per beam (issue 34 item 2)."""
import csv
import functools
import math

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.cad.parts import unit_id
from fabricate.export import write_bom, write_steel_cut_list
from fabricate.export.bars import (SPLICE, Piece, bar_measures, check_bar_plan, cutting_plan, write_bar_cutting,
                                   write_bar_order)
from fabricate.export.gasket import gasket_measures, gasket_table, write_gasket_schedule

BARS = {"stock_lengths_mm": [6000.0], "kerf_mm": 3.0, "end_trim_mm": 10.0}
TUBE = dict(connection="hub", hub="tube", radius_mm=90.0, wall_mm=8.0, cap_mm=12.0)
RHS = dict(section="rhs", web_mm=8, flange_mm=8, flange_width_mm=100)


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _put(path, rows):
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def _pieces(lengths, section="RHS 200x100x8"):
    return [Piece(f"B{i + 1:04d}", section, "S355J2", float(L), 30.0) for i, L in enumerate(lengths)]


def _fits(bar):
    k = len(bar.pieces)
    return sum(p.length for p in bar.pieces) + (k - 1) * bar.kerf + 2 * bar.trim <= bar.stock + 1e-9


# -- the cutting plan on known lengths -------------------------------------------------------------
def test_two_pieces_a_bar_when_two_fit_and_three_do_not():
    # 2 x 2900 + kerf 3 + 2 trims of 10 = 5823 <= 6000 < 3 x 2900: 8 pieces need exactly 4 bars
    plan = cutting_plan(_pieces([2900.0] * 8), BARS)
    assert len(plan.bars) == 4 and all(len(b.pieces) == 2 and b.stock == 6000.0 for b in plan.bars)
    assert all(_fits(b) for b in plan.bars)
    assert sorted(plan.bar_of()) == [p.id for p in _pieces([2900.0] * 8)]
    assert plan.bars[0].offcut == pytest.approx(6000 - 5823)


def test_a_piece_that_fills_a_bar_exactly_fits_and_a_tenth_more_does_not():
    exact = cutting_plan(_pieces([5980.0, 5980.0]), BARS)        # 6000 - 2 trims
    assert [len(b.pieces) for b in exact.bars] == [1, 1] and not exact.splices
    over = cutting_plan(_pieces([5980.1]), BARS)
    assert [b.id for b in over.bars] == [SPLICE] and over.bars[0].stock is None


def test_each_bar_is_the_shortest_stock_that_holds_its_pieces():
    # on 12 m bars: [7000, 4000] (11023 mm used) and [4000]; the second fits a 6 m bar
    plan = cutting_plan(_pieces([4000.0, 7000.0, 4000.0]), {"stock_lengths_mm": [6000, 12000]})
    assert sorted(b.stock for b in plan.bars) == [6000.0, 12000.0]
    assert sorted(len(b.pieces) for b in plan.bars) == [1, 2] and all(_fits(b) for b in plan.bars)
    # four 2900s fit one 12 m bar (11629 mm): one bar, not two of 6 m (the same length bought)
    assert [len(b.pieces) for b in cutting_plan(_pieces([2900.0] * 4), {"stock_lengths_mm": [6000, 12000]}).bars] == [4]


def test_sections_and_grades_never_share_a_bar():
    pieces = _pieces([1000.0] * 2) + _pieces([1000.0] * 2, "RHS 200x100x10") + [
        Piece("B0009", "RHS 200x100x8", "S235JR", 1000.0)]
    plan = cutting_plan(pieces, BARS)
    assert len(plan.bars) == 3
    for b in plan.bars:
        assert len({(p.section, p.grade) for p in b.pieces}) == 1 and (b.section, b.grade) == (
            b.pieces[0].section, b.pieces[0].grade)


def test_a_beam_longer_than_the_longest_bar_is_reported_not_placed():
    plan = cutting_plan(_pieces([13000.0, 2000.0]), {"stock_lengths_mm": [6000, 12000]})
    assert plan.bar_of()["B0001"] == SPLICE and [p.id for p in plan.splices] == ["B0001"]
    assert plan.bar_of()["B0002"].startswith("BAR")


# -- a roof: files, the cut list's bar, the check from the files -------------------------------------
@functools.lru_cache(maxsize=None)
def rhs_parts():
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node=TUBE, beam=RHS))


def _written(folder, parts, bars=None):
    write_bom(parts, folder / "bom.csv")
    write_steel_cut_list(parts, folder / "steel_cut_list.csv", bars=bars)
    order = write_bar_order(parts, folder / "bar_order.csv", bars=bars)
    cutting = write_bar_cutting(parts, folder / "bar_cutting.csv", bars=bars)
    return order, cutting


def test_every_beam_and_hub_tube_is_on_one_bar_named_in_the_cut_list(tmp_path):
    parts = rhs_parts()
    order, _ = _written(tmp_path, parts)
    cut = _rows(tmp_path / "steel_cut_list.csv")
    bars = {r["bar"]: r for r in _rows(tmp_path / "bar_cutting.csv")}
    beams = _beams(parts)
    tubes = {g.ids[i] for g in parts.of_kind("node") if g.member == "tube" for i in range(len(g))}
    on_bars = [pid for r in bars.values() for pid in r["ids"].split()]
    assert sorted(on_bars) == sorted(beams | tubes)                       # each once
    for r in cut:
        if r["id"] in beams | tubes:
            b = bars[r["bar"]]
            at = b["ids"].split().index(r["id"])
            assert b["lengths_mm"].split()[at] == r["length_mm"] and b["section"] == r["section"]
        else:
            assert r["bar"] == ""                                          # plates and caps: cut from sheet
    for b in bars.values():
        L = np.array(b["lengths_mm"].split(), dtype=float)
        used = L.sum() + (len(L) - 1) * float(b["kerf_mm"]) + 2 * float(b["end_trim_mm"])
        assert used <= float(b["stock_length_mm"]) + 0.05 * len(L)
        assert float(b["offcut_mm"]) == pytest.approx(float(b["stock_length_mm"]) - used, abs=0.1)
    lines = _rows(tmp_path / "bar_order.csv")
    assert sum(int(r["bars"]) for r in lines) == len(bars) == order["bars"]
    for r in lines:   # the bought length and its mass, the pieces' length
        on = [b for b in bars.values() if (b["section"], b["stock_length_mm"]) == (r["section"], r["stock_length_mm"])]
        assert int(r["bars"]) == len(on) and int(r["pieces"]) == sum(int(b["pieces"]) for b in on)
        bought = float(r["stock_length_mm"]) * len(on)
        assert float(r["bought_length_m"]) == pytest.approx(bought / 1000, abs=1e-3)
        pieces = sum(float(x) for b in on for x in b["lengths_mm"].split())
        assert float(r["waste_pct"]) == pytest.approx(100 * (bought - pieces) / bought, abs=0.06)
    assert check_bar_plan(tmp_path)["pass"] is True


def test_the_check_fails_on_a_tampered_plan(tmp_path):
    _written(tmp_path, rhs_parts())
    good = _rows(tmp_path / "bar_cutting.csv")
    assert check_bar_plan(tmp_path)["pass"] is True

    def fails(rows, words):
        _put(tmp_path / "bar_cutting.csv", rows)
        got = check_bar_plan(tmp_path)
        assert got["pass"] is False and any(words in p for p in got["problems"]), got["problems"]

    two = next(i for i, r in enumerate(good) if int(r["pieces"]) >= 2)
    r = dict(good[two])
    ids, lengths = r["ids"].split(), r["lengths_mm"].split()
    dropped = dict(r, ids=" ".join(ids[1:]), lengths_mm=" ".join(lengths[1:]), pieces=str(len(ids) - 1))
    fails(good[:two] + [dropped] + good[two + 1:], "on no bar")                       # a beam left out
    fails(good + [dict(r, bar="BAR9999")], "is also on")                               # a bar cut twice
    used = float(r["used_mm"])
    short = dict(r, stock_length_mm=f"{math.floor(used) - 1}")
    fails(good[:two] + [short] + good[two + 1:], "> stock")                           # more than the bar holds
    longer = dict(r, lengths_mm=" ".join([f"{float(lengths[0]) + 1:.1f}"] + lengths[1:]))
    fails(good[:two] + [longer] + good[two + 1:], "the cut list")                     # not the cut list's length


def test_the_run_check_holds_the_plan_to_the_cut_list(tmp_path):
    from fabricate.check import check_outputs

    _written(tmp_path, rhs_parts())
    assert check_outputs(tmp_path)["checks"]["bars"]["pass"] is True
    cut = _rows(tmp_path / "steel_cut_list.csv")
    moved = next(r for r in cut if r["bar"].startswith("BAR"))
    moved["bar"] = "BAR0999"
    _put(tmp_path / "steel_cut_list.csv", cut)
    got = check_outputs(tmp_path)
    assert got["checks"]["bars"]["pass"] is False and "bars" in got["failed"]


def test_beams_longer_than_every_bar_are_splices_in_every_file_and_a_warning(tmp_path):
    parts = rhs_parts()
    short = {"stock_lengths_mm": [3000], "kerf_mm": 3, "end_trim_mm": 10}
    long_ids = {u for u in _beams(parts) if float(f"{_length(parts, u):.1f}") > 2980.0}
    assert long_ids and long_ids != _beams(parts)
    order, cutting = _written(tmp_path, parts, short)
    assert sorted(cutting["splice_needed"]) == sorted(long_ids)
    cut = {r["id"]: r for r in _rows(tmp_path / "steel_cut_list.csv")}
    assert {i for i, r in cut.items() if r["bar"] == SPLICE} == long_ids
    splice_lines = [r for r in _rows(tmp_path / "bar_order.csv") if r["stock_length_mm"] == SPLICE]
    assert sum(int(r["pieces"]) for r in splice_lines) == len(long_ids)
    assert check_bar_plan(tmp_path)["pass"] is True                  # reported, not hidden: the plan holds
    m = bar_measures(parts, short)["bar_length"]
    assert m["pass"] is False and not m["enforced"] and m["tolerance"] == 2980.0
    assert bar_measures(parts, None)["bar_length"]["pass"] is True  # 12 m bars hold every beam of this dome


def _beams(parts):
    return {unit_id(b.id) for b in parts.beams}


def _length(parts, uid):
    from fabricate.export.schedules import beam_lengths

    return beam_lengths(parts)[1][uid]


# -- the gasket: a folded roof of known angles ---------------------------------------------------------
SLOPES = (0.0, 4.0, 10.0)
"""Slopes (deg) of a roof folded along lines of constant x: panels meet at 4 and 6 deg."""


@functools.lru_cache(maxsize=None)
def folded_parts():
    from optimize.mesh import Mesh

    from fabricate.offset import offset_structure

    x = np.arange(4) * 1000.0
    z = np.concatenate([[0.0], np.cumsum(1000.0 * np.tan(np.radians(SLOPES)))])
    V = np.array([[xi, y, zi] for xi, zi in zip(x, z) for y in (0.0, 1500.0, 3000.0)])
    F = [[i * 3 + j, (i + 1) * 3 + j, (i + 1) * 3 + j + 1, i * 3 + j + 1] for i in range(3) for j in range(2)]
    return build_parts(offset_structure(Mesh(V, F, name="folded"), (0.0, -200.0)), PartSpec())


def test_the_fold_and_the_gasket_step_of_a_folded_roof(tmp_path):
    parts = folded_parts()
    g = gasket_table(parts, {"bite_mm": 25.0, "max_fold_deg": 5.0})
    E = parts.mesh.topology.edges[g["edge"]]
    X = parts.mesh.V[E][..., 0]                                # x of both ends
    fold_line = (X[:, 0] == X[:, 1]) & np.isin(X[:, 0], (1000.0, 2000.0)) & ~np.isnan(g["fold"])
    assert fold_line.sum() == 4
    expect = np.where(X[:, 0] == 1000.0, SLOPES[1] - SLOPES[0], SLOPES[2] - SLOPES[1])
    np.testing.assert_allclose(g["fold"][fold_line], expect[fold_line], atol=1e-9)
    # the beam plane bisects the panels (conical): each tilts by half the fold on the flat top
    np.testing.assert_allclose(g["tilt"][fold_line], np.repeat(expect[fold_line, None] / 2, 2, axis=1), atol=1e-9)
    np.testing.assert_allclose(g["step"][fold_line], 25.0 * np.tan(np.radians(g["tilt"][fold_line])), rtol=1e-12)
    inner = ~fold_line & ~np.isnan(g["fold"])                  # two panels in one plane
    assert inner.sum() == 3 and np.abs(g["fold"][inner]).max() < 1e-9
    assert [g["ids"][k] for k in np.flatnonzero(g["flagged"])] == [
        g["ids"][k] for k in np.flatnonzero(fold_line & (expect > 5.0))]
    facts = write_gasket_schedule(parts, tmp_path / "gasket.csv", {"bite_mm": 25.0, "max_fold_deg": 5.0})
    rows = {r["id"]: r for r in _rows(tmp_path / "gasket.csv")}
    assert set(rows) == _beams(parts) and facts["flagged"] == 2
    for k in np.flatnonzero(fold_line):
        r = rows[g["ids"][k]]
        assert float(r["fold_deg"]) == pytest.approx(expect[k], abs=0.005)
        assert float(r["step_a_mm"]) == pytest.approx(25.0 * np.tan(np.radians(expect[k] / 2)), abs=0.005)
        assert ("beyond" in r["flags"]) == (expect[k] > 5.0)
    m = gasket_measures(parts, {"max_fold_deg": 5.0})["gasket_fold"]
    assert m["pass"] is False and not m["enforced"] and m["max"] == pytest.approx(6.0, abs=1e-9)
    assert gasket_measures(parts, {"max_fold_deg": 6.5})["gasket_fold"]["pass"] is True


def test_the_outputs_config_takes_bars_and_gasket():
    from fabricate.app.config import OutputsSection

    cfg = OutputsSection.model_validate({})
    assert cfg.bars.stock_lengths_mm == (6000.0, 12000.0) and cfg.gasket.max_fold_deg == 2.0
    cfg = OutputsSection.model_validate({"bars": {"stock_lengths_mm": [8000]}, "gasket": {"bite_mm": 15}})
    assert cfg.bars.stock_lengths_mm == (8000.0,) and cfg.bars.kerf_mm == 3.0 and cfg.gasket.bite_mm == 15.0
    with pytest.raises(Exception, match="end_trim_mm"):
        OutputsSection.model_validate({"bars": {"stock_lengths_mm": [100], "end_trim_mm": 60}})
