"""Property-based tests of every mesh reader: any bytes end in a valid Mesh or a one-line MeshError,
within a memory and a time cap.

Inputs come from two sources:

- mutated real files: small meshes written in every format (OBJ, OFF, PLY ascii / binary
  little- and big-endian, STL ascii / binary), then truncated, byte-flipped, spliced with
  hostile tokens (huge and negative counts and indices, NaN, Inf, 1e308, CRLF, a BOM,
  unicode, empty lines, a 5000-digit token), numbers replaced by hostile ones, binary
  words overwritten;
- generated polygon soups written by hand in every format: 200-gon faces, duplicate
  faces, isolated vertices, non-manifold edges and vertices, out-of-range and negative
  indices, NaN/Inf/1e308 coordinates.

Each case runs in a worker process with ``RLIMIT_AS`` set to its size at start plus
:data:`MEM_CAP` (a reader that tries to allocate gigabytes gets a MemoryError, reported
as a failure, instead of taking the machine), a per-case time limit :data:`TIME_CAP`
(``setitimer`` in the worker, a kill from the parent as the fallback), and a traced
peak of Python + numpy memory that must stay below :data:`PER_BYTE` times the file's
size plus :data:`BASE` (memory proportional to the file).

The example budget is fixed and the search derandomized, so CI runs the same cases in
a few seconds.  A longer campaign: ``FUZZ_EXAMPLES=3000 pytest -s tests/test_fuzz_readers.py tests/test_fuzz_cosmetic.py``
prints, per input class, how many inputs were tried and how each ended.
"""
from __future__ import annotations

import json
import os
import re
import select
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[1]
MEM_CAP = 768 << 20  # address space a worker may add to its size at start (bytes)
TIME_CAP = 10.0  # seconds per case (traced: tracemalloc slows parsing several times)
PER_BYTE, BASE = 128, 24 << 20  # traced peak allowed: PER_BYTE x file size + BASE
CLEAN = ("mesh", "mesh_error")


# -- the worker: python tests/test_fuzz_readers.py --worker DIR --------------------------------------
def _worker(folder: str) -> None:  # pragma: no cover - runs in the subprocess
    import resource
    import signal
    import tracemalloc

    sys.path.insert(0, str(REPO))
    from optimize.errors import MeshError
    from optimize.mesh.io import read_mesh

    with open("/proc/self/statm") as fh:
        size = int(fh.read().split()[0]) * resource.getpagesize()
    resource.setrlimit(resource.RLIMIT_AS, (size + MEM_CAP, size + MEM_CAP))

    class Timeout(BaseException):
        pass

    def alarm(signum, frame):
        raise Timeout()

    signal.signal(signal.SIGALRM, alarm)
    out = sys.stdout
    for header in sys.stdin.buffer:
        ext, n = header.decode().split()
        data = sys.stdin.buffer.read(int(n))
        path = os.path.join(folder, f"case.{ext}")
        with open(path, "wb") as fh:
            fh.write(data)
        tracemalloc.start()
        signal.setitimer(signal.ITIMER_REAL, TIME_CAP)
        try:
            mesh = read_mesh(path)
            signal.setitimer(signal.ITIMER_REAL, 0)
            outcome, detail = "mesh", _invalid(mesh)
            if detail:
                outcome = "invalid_mesh"
        except MeshError as exc:
            signal.setitimer(signal.ITIMER_REAL, 0)
            msg = str(exc)
            ok = msg.startswith(path) and "\n" not in msg and "\r" not in msg
            outcome, detail = ("mesh_error" if ok else "bad_message"), msg[:300]
        except Timeout:
            outcome, detail = "timeout", f"over {TIME_CAP} s"
        except MemoryError as exc:
            signal.setitimer(signal.ITIMER_REAL, 0)
            outcome, detail = "memory", str(exc)[:300]
        except BaseException as exc:  # noqa: BLE001 - the point: anything else is a finding
            signal.setitimer(signal.ITIMER_REAL, 0)
            outcome, detail = "crash", f"{type(exc).__name__}: {exc}"[:300]
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        if outcome in CLEAN and peak > PER_BYTE * len(data) + BASE:
            outcome, detail = "memory", f"traced peak {peak} bytes for a {len(data)}-byte file"
        out.write(json.dumps({"outcome": outcome, "detail": detail, "peak": peak}) + "\n")
        out.flush()


def _invalid(mesh) -> str:  # pragma: no cover - runs in the subprocess
    """Why ``mesh`` is not a valid mesh ('' when it is)."""
    V, F = mesh.V, mesh.F
    if V.ndim != 2 or V.shape[1] != 3 or not len(V) or not len(F):
        return f"shapes {V.shape} {F.shape}"
    if not np.isfinite(V).all():
        return "non-finite vertex"
    if F.max() >= len(V) or F.min() < -1 or (mesh.face_sizes < 3).any():
        return "bad face indices"
    mesh.topology  # builds (and checks) the connectivity
    return ""


class Worker:
    """One worker process, restarted when a case kills it or hangs it."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.proc = None

    def start(self):
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", PYTHONPATH=str(REPO))
        self.proc = subprocess.Popen([sys.executable, __file__, "--worker", str(self.folder)],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env)

    def run(self, ext: str, data: bytes) -> dict:
        if self.proc is None or self.proc.poll() is not None:
            self.start()
        try:
            self.proc.stdin.write(f"{ext} {len(data)}\n".encode() + data)
            self.proc.stdin.flush()
            ready, _, _ = select.select([self.proc.stdout], [], [], TIME_CAP + 20)
            line = self.proc.stdout.readline() if ready else b""
        except BrokenPipeError:
            line = b""
        if not line:
            hung = self.proc.poll() is None
            self.stop()
            return {"outcome": "hang" if hung else "died", "detail": "", "peak": 0}
        return json.loads(line)

    def stop(self):
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()
            self.proc = None


# -- the seed files ------------------------------------------------------------------------------------
def _stl_ascii(tris) -> bytes:
    lines = ["solid seed"]
    for t in tris:
        lines += ["facet normal 0 0 1", " outer loop"] + [f"  vertex {a:.9g} {b:.9g} {c:.9g}" for a, b, c in t]
        lines += [" endloop", "endfacet"]
    return ("\n".join(lines + ["endsolid seed"]) + "\n").encode()


def _stl_binary(tris) -> bytes:
    with np.errstate(over="ignore"):  # 1e308 becomes inf in float32, as a modeller would write it
        tris = np.asarray(tris, dtype="<f4").reshape(-1, 9)
    rec = np.zeros(len(tris), dtype=[("n", "<f4", 3), ("v", "<f4", 9), ("a", "<u2")])
    rec["v"] = tris
    return b"seed".ljust(80, b" ") + struct.pack("<I", len(tris)) + rec.tobytes()


def _seeds() -> dict[str, tuple[str, bytes]]:
    """name -> (extension, bytes) of small real files in every format."""
    import tempfile

    from optimize.modelling import shapes
    from optimize.mesh.io import write_mesh

    meshes = {"grid": shapes.grid(4, 3, height=lambda x, y: 0.1 * x * y, name="grid"),
              "dome": shapes.perturbed(shapes.revolution(shapes.dome_profile(k=3), 5), 0.05, seed=3)}
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name, mesh in meshes.items():
            for label, ext, kw in [("obj", "obj", {}), ("off", "off", {}), ("ply-ascii", "ply", {"binary": False}),
                                   ("ply-le", "ply", {})]:
                path = Path(tmp) / f"{name}.{ext}"
                write_mesh(path, mesh, **kw)
                out[f"{name}-{label}"] = (ext, path.read_bytes())
            from optimize.mesh.io.ply import format_ply

            out[f"{name}-ply-be"] = ("ply", format_ply(mesh, "binary_big_endian"))
            tris = mesh.V[mesh.triangulate()]
            out[f"{name}-stl-ascii"] = ("stl", _stl_ascii(tris))
            out[f"{name}-stl-binary"] = ("stl", _stl_binary(tris))
    return out


SEEDS = _seeds() if __name__ != "__main__" else {}
HOSTILE = [b"99999999999999999999", b"4294967295", b"2147483648", b"-1", b"-2147483648", b"0", b"nan",
           b"inf", b"-inf", b"1e308", b"-1e308", b"1e-320", b"\r\n", b"\xef\xbb\xbf", "\u00b2".encode(),
           "\u00e9\u4e2d".encode(), b"\n\n\n", b"\x00", b"#", b"\\\n", b"/", b" ", b"9" * 5000, b"A" * 200000,
           b"element vertex 100000000\n", b"property list uint int vertex_indices\n", b"f 1 2 3\n",
           b"solid loop\n", b"vertex", b"endloop"]
WORDS = [b"\xff\xff\xff\xff", b"\xff\xff\xff\x7f", b"\x00\x00\x00\x80", b"\x00\x00\xc0\x7f",
         b"\x00\x00\x80\x7f", b"\xff" * 8, b"\x00" * 8, b"\x7f\xef\xff\xff\xff\xff\xff\xff"]
HEADER_LINES = [b"element junk 4000000000\n", b"element junk 5\n", "element vertex \u00b2\n".encode(),
                b"property list uint int vertex_indices\n", b"property float128 w\n", b"comment \xff\xfe\n",
                b"element face 4294967295\n", b"property list uchar uint extra\n", b"format ascii 2.0\n",
                b"4000000000 4000000000 0\n", b"mtllib a.mtl\n", "o \u00e9\n".encode(), b"\n"]
NUMBER = re.compile(rb"[-+]?\d+(\.\d*)?([eE][-+]?\d+)?")


# -- hypothesis strategies -------------------------------------------------------------------------
from _fuzz_common import FUZZ, TALLY, Case, print_tally  # noqa: E402
from hypothesis import given  # noqa: E402
from hypothesis import strategies as st  # noqa: E402


@st.composite
def mutated(draw):
    """(class labels, extension, bytes): a seed file with 1-3 mutations."""
    name = draw(st.sampled_from(sorted(SEEDS)))
    ext, data = SEEDS[name]
    b = bytearray(data)
    labels = []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["truncate", "flip", "delete", "insert", "number", "word", "crlf", "bom",
                                     "duplicate-line", "header-line"]))
        n = len(b)
        i = draw(st.integers(0, max(n - 1, 0)))
        if kind == "truncate":
            del b[i:]
        elif kind == "flip":
            if n:
                b[i] = draw(st.integers(0, 255))
        elif kind == "delete":
            del b[i:i + draw(st.integers(1, 40))]
        elif kind == "insert":
            b[i:i] = draw(st.sampled_from(HOSTILE))
        elif kind == "number":
            spans = [m.span() for m in NUMBER.finditer(bytes(b[:4096]))]
            if spans:
                s, e = draw(st.sampled_from(spans))
                b[s:e] = draw(st.sampled_from(HOSTILE[:12]))
        elif kind == "word":
            w = draw(st.sampled_from(WORDS))
            b[i:i + len(w)] = w
        elif kind == "crlf":
            b = bytearray(bytes(b).replace(b"\n", b"\r\n"))
        elif kind == "bom":
            b[0:0] = b"\xef\xbb\xbf"
        elif kind == "header-line":  # a hostile line among the first ones (PLY / OFF headers)
            ends = [k + 1 for k, c in enumerate(bytes(b[:400])) if c == 10] or [0]
            j = draw(st.sampled_from(ends))
            b[j:j] = draw(st.sampled_from(HEADER_LINES))
        else:
            lines = bytes(b).split(b"\n")
            j = draw(st.integers(0, len(lines) - 1))
            lines.insert(j, lines[j])
            b = bytearray(b"\n".join(lines))
        labels.append(f"mutated {kind}")
    return Case(([f"seed {name.split('-', 1)[1]}"] + labels, ext, bytes(b)))


_COORD = st.one_of(st.floats(-10, 10, allow_nan=False), st.sampled_from([float("nan"), float("inf"), 1e308,
                                                                         -1e308, 1e15, 0.0]))


@st.composite
def soup(draw):
    """(class labels, extension, bytes): a generated polygon soup with hostile features."""
    n = draw(st.integers(3, 40))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    V = rng.normal(size=(n, 3))
    labels = []
    faces = [list(map(int, rng.choice(n, size=min(n, int(rng.integers(3, 6))), replace=False)))
             for _ in range(draw(st.integers(1, 30)))]
    features = draw(st.sets(st.sampled_from(["200-gon", "duplicate faces", "isolated vertices",
                                             "non-manifold edge", "non-manifold vertex", "bad index",
                                             "hostile coordinate", "grid", "huge polygon"]), max_size=3))
    if "grid" in features:  # a clean 4 x 4 grid (valid), then the other features on top
        g = np.arange(16).reshape(4, 4)
        V = np.c_[np.indices((4, 4)).reshape(2, -1).T, np.zeros(16)].astype(float)
        n = 16
        faces = [[int(g[i, j]), int(g[i + 1, j]), int(g[i + 1, j + 1]), int(g[i, j + 1])]
                 for i in range(3) for j in range(3)]
    if "200-gon" in features:
        t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
        V = np.r_[V, np.c_[np.cos(t), np.sin(t), np.zeros(200)] * 5 + [20, 0, 0]]
        faces.append(list(range(n, n + 200)))
        n += 200
    if "huge polygon" in features:  # one big face among many triangles: padding would blow up
        k, m = draw(st.integers(300, 3000)), draw(st.integers(100, 1500))
        t = np.linspace(0, 2 * np.pi, k, endpoint=False)
        V = np.r_[V, np.c_[np.cos(t), np.sin(t), np.zeros(k)] * 50 + [200, 0, 0]]
        faces.append(list(range(n, n + k)))
        n += k
        strip = np.arange(n, n + m + 2)
        V = np.r_[V, np.c_[np.arange(m + 2) // 2, np.arange(m + 2) % 2, np.zeros(m + 2)] + [0, 100, 0]]
        faces += [[int(strip[i]), int(strip[i + 1 + i % 2]), int(strip[i + 2 - i % 2])] for i in range(m)]
        n += m + 2
    if "duplicate faces" in features:
        faces.append(list(faces[0]))
    if "isolated vertices" in features:
        V = np.r_[V, rng.normal(size=(3, 3)) + 50]
    if "non-manifold edge" in features:
        a, b = faces[0][:2]
        V = np.r_[V, [[9, 9, 9], [8, 9, 9]]]
        faces += [[a, b, len(V) - 2], [b, a, len(V) - 1]]
    if "non-manifold vertex" in features:
        a = faces[0][0]
        V = np.r_[V, [[30, 0, 0], [30, 1, 0], [31, 0, 1], [31, 1, 1]]]
        m = len(V)
        faces += [[a, m - 4, m - 3], [a, m - 2, m - 1]]
    if "bad index" in features:
        faces[-1][0] = draw(st.sampled_from([-1, -7, len(V), 2**31, 2**40]))
    if "hostile coordinate" in features:
        V[draw(st.integers(0, len(V) - 1)), draw(st.integers(0, 2))] = draw(_COORD)
    labels += [f"generated {f}" for f in sorted(features)] or ["generated plain soup"]
    fmt = draw(st.sampled_from(["obj", "off", "ply-ascii", "ply-le", "ply-be", "stl-ascii", "stl-binary"]))
    ext, data = _write_soup(fmt, V, faces)
    return Case((labels + [f"format {fmt}"], ext, data))


def _write_soup(fmt: str, V: np.ndarray, faces: list[list[int]]) -> tuple[str, bytes]:
    """Bytes of an unchecked polygon soup in ``fmt`` (the library's writers refuse bad meshes)."""
    vs = "".join("%r %r %r\n" % tuple(map(float, v)) for v in V)
    if fmt == "obj":
        return "obj", ("".join("v " + ln + "\n" for ln in vs.splitlines())
                       + "".join("f " + " ".join(str(i + 1 if i >= 0 else i) for i in f) + "\n"
                                 for f in faces)).encode()
    if fmt == "off":
        return "off", (f"OFF\n{len(V)} {len(faces)} 0\n" + vs
                       + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces)).encode()
    if fmt.startswith("ply"):
        enc = {"ply-ascii": "ascii", "ply-le": "binary_little_endian", "ply-be": "binary_big_endian"}[fmt]
        head = (f"ply\nformat {enc} 1.0\nelement vertex {len(V)}\nproperty double x\nproperty double y\n"
                f"property double z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\n"
                "end_header\n").encode()
        if enc == "ascii":
            return "ply", head + (vs + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n"
                                               for f in faces)).encode()
        e = "<" if enc.endswith("little_endian") else ">"
        body = V.astype(e + "f8").tobytes()
        for f in faces:
            f = [max(min(i, 2**31 - 1), -2**31) for i in f]
            body += struct.pack(f"{e}B{len(f)}i", len(f) % 256, *f)
        return "ply", head + body
    tris = [[V[f[0] % len(V)], V[f[j] % len(V)], V[f[j + 1] % len(V)]] for f in faces for j in range(1, len(f) - 1)]
    return "stl", (_stl_ascii(tris) if fmt == "stl-ascii" else _stl_binary(tris))


# -- the properties ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def worker(tmp_path_factory):
    w = Worker(tmp_path_factory.mktemp("fuzz"))
    yield w
    w.stop()
    if os.environ.get("FUZZ_EXAMPLES"):  # the campaign's figures (shown with -s)
        print_tally(CLEAN)


def _check(worker, case) -> None:
    labels, ext, data = case
    res = worker.run(ext, data)
    TALLY["all inputs", res["outcome"]] += 1
    for label in dict.fromkeys(labels):
        TALLY[label, res["outcome"]] += 1
    if res["outcome"] not in CLEAN:  # keep the input for a look by hand
        keep = worker.folder / f"failure-{len(list(worker.folder.glob('failure-*')))}.{ext}"
        keep.write_bytes(data)
        res["file"] = str(keep)
    assert res["outcome"] in CLEAN, (res, labels)


@FUZZ
@given(case=mutated())
def test_mutated_real_files_end_in_a_mesh_or_a_mesh_error(worker, case):
    _check(worker, case)


@FUZZ
@given(case=soup())
def test_generated_soups_end_in_a_mesh_or_a_mesh_error(worker, case):
    _check(worker, case)


def test_the_worker_reports_what_it_is_asked_to_catch(worker):
    """The harness itself can fail: a valid file is a mesh, a broken one a mesh error."""
    ext, data = SEEDS["grid-obj"]
    assert worker.run(ext, data)["outcome"] == "mesh"
    assert worker.run("off", b"OFF\n3 1 0\n0 0 0\n")["outcome"] == "mesh_error"


if __name__ == "__main__":  # pragma: no cover
    if sys.argv[1:2] == ["--worker"]:
        _worker(sys.argv[2])
