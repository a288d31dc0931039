"""The scaling curve of ``bench_optimize.py``: the default optimizer on perturbed domes of
revolution from 1,000 to 30,000 faces (100,000 with ``--large``), pq and conical, each size
in a fresh process, with its time per 1,000 faces and peak resident memory.

    python benchmarks/bench_optimize_scaling.py [--large]

``--scale`` is issue 31's scale table instead: pq and conical at 10k, 100k and 300k faces
(``--sizes``; ``--huge`` adds pq at 1M, which may take over 10 minutes), each case in a
fresh process, printing its status, max distance to the input (% of the bbox diagonal),
fairness ratio (result over input roughness), iterations, time of ``optimize_mesh``, the
linear solves' and the assembly's share of it, and the process's peak resident memory
(``ru_maxrss`` of that child, from ``os.wait4``).  ``--baseline DIR`` runs every case
also with the code in DIR (e.g. ``git worktree add /tmp/base <commit>``) in the same run,
before the current code, so the two are measured under the same load.  A case whose
resident memory passes ``--max-gib`` (default 16) is stopped and printed as such.

    nice python benchmarks/bench_optimize_scaling.py --scale [--huge] [--baseline /tmp/base]
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def cases_module(root: str | None = None):
    """``_optimize_cases`` of the repository at ``root`` (this one when None): it imports that
    repository's ``optimize``."""
    path = (Path(root) / "benchmarks" if root else HERE) / "_optimize_cases.py"
    spec = importlib.util.spec_from_file_location("_optimize_cases", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["_optimize_cases"] = mod
    spec.loader.exec_module(mod)
    return mod


def peak_rss_mib() -> float:
    """Peak resident memory of this process (VmHWM; ru_maxrss would include the parent's
    peak, which survives fork + exec)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def one(target, faces):
    cases = cases_module()
    mesh = cases.revolution(faces)
    r = cases.ours(mesh, target)
    r["peak_rss_mib"] = peak_rss_mib()
    print(json.dumps(r))


def scaling(args):
    sizes = [1000, 3000, 10000, 30000] + ([100000] if args.large else [])
    for target, sizes in (("pq", sizes), ("conical", [1000, 3000, 10000] + ([30000] if args.large else []))):
        print(f"\n{target} scaling curve (perturbed dome of revolution, one fresh process per size; "
              f"'max' is the {'planarity' if target == 'pq' else 'conical defect'}):")
        print(f"{'faces':>8s} {'seconds':>9s} {'s/1k faces':>10s} {'max':>10s} {'planarity':>10s} "
              f"{'nit':>4s} {'peak MiB':>9s}")
        for n in sizes:
            p = subprocess.run([sys.executable, __file__, "--one", target, str(n)], capture_output=True,
                               text=True)
            if p.returncode:
                print(f"{n:8d} failed: {p.stderr.strip().splitlines()[-1:]}", flush=True)
                continue
            r = json.loads(p.stdout.strip().splitlines()[-1])
            print(f"{r['faces']:8d} {r['seconds']:9.2f} {1000 * r['seconds'] / r['faces']:10.3f} "
                  f"{r['max']:10.2e} {r['planarity']:10.2e} {r['nit']:4d} {r['peak_rss_mib']:9.0f}",
                  flush=True)


def scale_one(target, faces, root, backend):
    """One case of the scale table (run in a child process): a JSON row on stdout."""
    cases = cases_module(root)
    from optimize import optimize_mesh

    mesh = cases.revolution(faces)
    t = time.perf_counter()
    res = optimize_mesh(mesh, target, linear_solver=backend)
    seconds = time.perf_counter() - t
    fair = res.defects.get("fairness", {})
    tm = getattr(res, "timings", {}) or {}
    print(json.dumps({"faces": mesh.n_faces, "status": res.status, "nit": res.nit, "seconds": seconds,
                      "distance": float(res.defects["distance"]["max_relative"]),
                      "fair_ratio": float(fair["result"] / fair["input"]) if fair.get("input") else float("nan"),
                      "solve": float(tm.get("solve", float("nan"))),
                      "assemble": float(tm.get("assemble", float("nan")))}))


def run_case(cmd, max_gib, timeout):
    """Run ``cmd``; (returncode, stdout, stderr, peak MiB from ru_maxrss, note).  The child is
    killed when its resident memory passes ``max_gib`` or it runs past ``timeout`` seconds."""
    with tempfile.TemporaryFile("w+") as fo, tempfile.TemporaryFile("w+") as fe:
        p = subprocess.Popen(cmd, stdout=fo, stderr=fe, text=True)
        note, t0 = "", time.monotonic()
        while True:
            pid, status, ru = os.wait4(p.pid, os.WNOHANG)
            if pid:
                break
            try:
                rss = next(int(x.split()[1]) for x in Path(f"/proc/{p.pid}/status").read_text().splitlines()
                           if x.startswith("VmRSS:")) / 2 ** 20
            except (OSError, StopIteration):
                rss = 0.0
            if rss > max_gib and not note:
                note = f"stopped: resident memory passed {max_gib:g} GiB"
                p.kill()
            elif time.monotonic() - t0 > timeout and not note:
                note = f"stopped after {timeout:g} s"
                p.kill()
            time.sleep(0.2)
        p.returncode = os.waitstatus_to_exitcode(status)
        fo.seek(0)
        fe.seek(0)
        return p.returncode, fo.read(), fe.read(), ru.ru_maxrss / 1024, note


def scale_table(args):
    sizes = args.sizes
    todo = [(t, n) for t in args.targets for n in sizes]
    if args.huge and "pq" in args.targets:
        todo.append(("pq", 1_000_000))
    codes = ([("before", args.baseline)] if args.baseline else []) + [("after" if args.baseline else "now", None)]
    print(f"scale table (perturbed dome of revolution, linear_solver={args.backend}, one fresh process per "
          f"case; dist = max distance to the input, % of the bbox diagonal; fair = result/input roughness; "
          f"time = optimize_mesh; solve/assemble = the Gauss-Newton iteration's linear solves and assembly; "
          f"peak = ru_maxrss of the case's process); {time.strftime('%Y-%m-%d %H:%M')}", flush=True)
    head = (f"{'target':8s} {'faces':>8s} {'code':7s} {'status':10s} {'dist %':>8s} {'fair':>6s} {'nit':>4s} "
            f"{'time s':>8s} {'solve s':>8s} {'asm s':>7s} {'peak MiB':>9s}")
    print(head)
    print("-" * len(head), flush=True)
    for target, n in todo:
        for code, root in codes:
            cmd = [sys.executable, __file__, "--scale-one", target, str(n), "--backend", args.backend]
            if root:
                cmd += ["--root", root]
            rc, out, err, peak, note = run_case(cmd, args.max_gib, args.timeout)
            if rc or note:
                why = note or (err.strip().splitlines() or ["exit %d" % rc])[-1]
                print(f"{target:8s} {n:8d} {code:7s} failed: {why} (peak {peak:.0f} MiB)", flush=True)
                continue
            r = json.loads(out.strip().splitlines()[-1])
            print(f"{target:8s} {r['faces']:8d} {code:7s} {r['status']:10s} {100 * r['distance']:8.3f} "
                  f"{r['fair_ratio']:6.3f} {r['nit']:4d} {r['seconds']:8.1f} {r['solve']:8.1f} "
                  f"{r['assemble']:7.1f} {peak:9.0f}", flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--large", action="store_true", help="scaling curve up to 100k faces")
    ap.add_argument("--scale", action="store_true", help="issue 31's scale table (10k, 100k, 300k faces)")
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 300_000],
                    help="face counts of the scale table")
    ap.add_argument("--targets", nargs="+", default=["pq", "conical"], help="targets of the scale table")
    ap.add_argument("--huge", action="store_true", help="scale table: also pq at 1M faces (over 10 minutes)")
    ap.add_argument("--baseline", metavar="DIR", help="scale table: also run every case with the code in DIR")
    ap.add_argument("--backend", default="auto", help="scale table: linear_solver (auto, pardiso, superlu, ...)")
    ap.add_argument("--max-gib", type=float, default=16.0, help="scale table: stop a case above this resident memory")
    ap.add_argument("--timeout", type=float, default=3600.0, help="scale table: stop a case after this many seconds")
    ap.add_argument("--one", nargs=2, metavar=("TARGET", "FACES"), help=argparse.SUPPRESS)
    ap.add_argument("--scale-one", nargs=2, metavar=("TARGET", "FACES"), help=argparse.SUPPRESS)
    ap.add_argument("--root", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        return one(args.one[0], int(args.one[1]))
    if args.scale_one:
        return scale_one(args.scale_one[0], int(args.scale_one[1]), args.root, args.backend)
    if args.scale:
        return scale_table(args)
    scaling(args)


if __name__ == "__main__":
    main()
