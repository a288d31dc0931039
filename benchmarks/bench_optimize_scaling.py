"""The scaling curve of ``bench_optimize.py``: the default optimizer on perturbed domes of
revolution from 1,000 to 30,000 faces (100,000 with ``--large``), pq and conical, each size
in a fresh process, with its time per 1,000 faces and peak resident memory.

    python benchmarks/bench_optimize_scaling.py [--large]
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
from pathlib import Path

from _optimize_cases import ours, revolution


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
    mesh = revolution(faces)
    r = ours(mesh, target)
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--large", action="store_true", help="scaling curve up to 100k faces")
    ap.add_argument("--one", nargs=2, metavar=("TARGET", "FACES"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        return one(args.one[0], int(args.one[1]))
    scaling(args)


if __name__ == "__main__":
    main()
