"""ifcopenshell from two threads of one process (a batch's jobs on one Dask worker): two runs write
and check their IFC files at the same time, both checks pass, and ifcopenshell is left as it was.

``ifcopenshell.validate`` switches the process-wide feature ``use_attribute_value_derived`` on and,
when it returns, back to what it found.  Two validations at once: the second finds it on; the
first puts it off under the second, whose file then fails ("Attribute is derived in subtype"); the
second leaves it on, and every later ``get_info`` gives ``attribute_value_derived`` objects (which
do not sort) where a subtype derives an attribute (``IfcSIUnit.Dimensions``, the sub-context's
``WorldCoordinateSystem``) instead of None: the failures of ``test_ifc_text.py`` after
``test_batch.py``.

The test below makes that interleaving happen, by events, not by timing: the first thread to
switch the feature on waits inside its validation until the other thread has come to ifcopenshell,
either in its own validation (no lock: the failure above, every time) or waiting for
:func:`fabricate.export.ifc.ifcopenshell_alone` (then it goes on, and the other runs after it).
"""
from __future__ import annotations

import threading

import pytest
from cad_fixtures import dome_parts

import fabricate.export.ifc as ifc
from fabricate.export import write_bom
from fabricate.export.bom import read_bom
from fabricate.export.exchange_check import check_ifc

ifcopenshell = pytest.importorskip("ifcopenshell")
from ifcopenshell import ifcopenshell_wrapper  # noqa: E402

DERIVED = "use_attribute_value_derived"
HANG = 60.0
"""Seconds any one wait may take before the test gives up: only a guard against a hang (each wait
ends on an event that the other thread sets a few milliseconds later)."""


class _Gate:
    """Holds the first validation until the other thread reaches ifcopenshell, then the other
    validation until the first has put the feature back.

    ``set_feature`` replaces ifcopenshell's; ``lock`` replaces :data:`fabricate.export.ifc._LOCK` (a
    re-entrant lock that notes who waits for it)."""

    def __init__(self):
        self.real_set = ifcopenshell_wrapper.set_feature
        self.real_lock = threading.RLock()
        self.cond = threading.Condition()
        self.first: threading.Thread | None = None
        self.waiting: set[threading.Thread] = set()    # threads waiting for (or in) ifcopenshell_alone
        self.second_validates = False
        self.restored = threading.Event()
        self.hung: list[str] = []

    def set_feature(self, name, value):
        me = threading.current_thread()
        if name != DERIVED:
            return self.real_set(name, value)
        with self.cond:
            if value and self.first is None:
                self.first = me
            elif value and me is not self.first:
                self.second_validates = True
                self.cond.notify_all()
        self.real_set(name, value)
        if me is self.first and value:                 # hold the first validation
            with self.cond:
                if not self.cond.wait_for(lambda: self.second_validates or self.waiting - {me}, HANG):
                    self.hung.append("the other thread never reached ifcopenshell")
        elif me is self.first:
            self.restored.set()
        elif value and not self.restored.wait(HANG):   # the second validation: after the first's end
            self.hung.append("the first validation never ended")

    def __enter__(self):
        me = threading.current_thread()
        with self.cond:
            self.waiting.add(me)
            self.cond.notify_all()
        self.real_lock.acquire()
        return self

    def __exit__(self, *exc):
        with self.cond:
            self.waiting.discard(threading.current_thread())
        self.real_lock.release()


def test_two_threads_write_and_check_ifc_at_once_and_leave_ifcopenshell_as_it_was(tmp_path, monkeypatch):
    parts = dome_parts(4, 2)
    gate = _Gate()
    results: dict[int, dict] = {}
    errors: list[BaseException] = []

    def run(k: int) -> None:
        try:
            folder = tmp_path / f"run{k}"
            folder.mkdir()
            ifc.write_ifc(parts, folder / "model.ifc")
            write_bom(parts, folder / "bom.csv")
            results[k] = check_ifc(folder / "model.ifc", read_bom(folder / "bom.csv"), full=True)
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    assert ifcopenshell_wrapper.get_feature(DERIVED) is False
    monkeypatch.setattr(ifcopenshell_wrapper, "set_feature", gate.set_feature)
    monkeypatch.setattr(ifc, "_LOCK", gate, raising=False)
    try:
        threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(HANG)
        left_on = ifcopenshell_wrapper.get_feature(DERIVED)
    finally:
        gate.real_set(DERIVED, False)   # a failure here must not fail the tests after it
    assert not errors and not gate.hung, (errors, gate.hung)
    assert gate.first is not None, "no validation ran"
    for k in range(2):
        assert results[k]["pass"] and results[k]["bad_schema"] == [], results[k]
    assert left_on is False

    # what test_ifc_text.py reads afterwards: an attribute a subtype derives is None in get_info
    f = ifcopenshell.open(str(tmp_path / "run0" / "model.ifc"))
    sub, = f.by_type("IfcGeometricRepresentationSubContext")
    info = sub.get_info(recursive=False)
    assert [info[k] for k in ("CoordinateSpaceDimension", "Precision", "WorldCoordinateSystem", "TrueNorth")] == \
        [None] * 4
    assert [u.get_info(recursive=False)["Dimensions"] for u in f.by_type("IfcSIUnit")] == [None] * 5


def test_ifcopenshell_alone_puts_the_feature_back_when_ifcopenshell_raises():
    """``validate`` restores the feature only when it returns; a raise half-way must not leave it on."""
    with pytest.raises(RuntimeError, match="half-way"):
        with ifc.ifcopenshell_alone():
            ifcopenshell_wrapper.set_feature(DERIVED, True)
            raise RuntimeError("half-way")
    assert ifcopenshell_wrapper.get_feature(DERIVED) is False
