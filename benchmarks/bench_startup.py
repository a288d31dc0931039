"""Start-up time of the command line: ``fabricate --help`` and ``fabricate measure MESH``.

Each command runs in a fresh interpreter ``--repeat`` times (best of), next
to ``python -c pass`` measured in the same run as the baseline: the ratio
says what the package adds to starting Python.  ``import optimize.errors``
and ``import optimize`` are shown too (the lazy package ``__init__`` files
keep both at interpreter start-up).  Goal: ``--help`` and ``measure`` well
under half a second.  On a shared machine the seconds are noisy; compare
the ratios.

    python benchmarks/bench_startup.py [--repeat 7] [--mesh PATH]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def best_of(argv: list[str], repeat: int) -> float:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    best = float("inf")
    for _ in range(repeat):  # a handful of runs
        t = time.perf_counter()
        subprocess.run(argv, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--mesh", default=str(ROOT / "configs" / "meshes" / "tunnel.off"),
                    help="mesh for fabricate measure (default: the shipped tunnel, 784 quads)")
    args = ap.parse_args()
    py = sys.executable
    cases = [("python -c pass (baseline)", [py, "-c", "pass"]),
             ("import optimize.errors", [py, "-c", "import optimize.errors"]),
             ("import optimize", [py, "-c", "import optimize"]),
             ("fabricate --help", [py, "-m", "fabricate", "--help"]),
             (f"fabricate measure {Path(args.mesh).name}", [py, "-m", "fabricate", "measure", args.mesh])]
    base = None
    print(f"best of {args.repeat}, load {os.getloadavg()[0]:.1f} (shared machine: seconds are noisy)")
    for name, argv in cases:
        s = best_of(argv, args.repeat)
        base = base or s
        print(f"{name:34s} {s:7.3f} s   x{s / base:5.1f} the baseline   +{s - base:6.3f} s")


if __name__ == "__main__":
    main()
