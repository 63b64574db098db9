"""hairfit.eval on 1M samples beside the Rust model's own rate (README, "Python package").

Times, on the same 1,000,000 random directions (|θ| ≤ 85°, all effects, cubic mode, 1 and 3
channels):

- ``hairfit.eval`` from NumPy arrays, one thread (RAYON_NUM_THREADS=1) and all cores;
- ``hairfit eval`` (the CLI, CSV text in and out: parsing and formatting included) on the same
  angles, one thread and all cores;
- with ``--rust-bench``, ``cargo bench --bench model -- lanes/`` (the model alone, one thread,
  criterion), as the README's eval section measures it.

Each timing is the median of ``--runs`` runs (each in a fresh process for the thread setting).

Usage (repository root, with the package installed): python python/bench_eval.py [--runs 5]
[--rows 1000000] [--rust-bench]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, sys, time
import numpy as np
import hairfit
rows, runs, params = int(sys.argv[1]), int(sys.argv[2]), json.loads(sys.argv[3])
rng = np.random.default_rng(1)
a = [rng.uniform(-85, 85, rows), rng.uniform(-180, 180, rows),
     rng.uniform(-85, 85, rows), rng.uniform(-180, 180, rows)]
hairfit.eval(params, *(x[:1000] for x in a))  # warm up
times = []
for _ in range(runs):
    t = time.perf_counter()
    s = hairfit.eval(params, *a)
    times.append(time.perf_counter() - t)
print(json.dumps(times))
"""


def params(channels: int) -> dict:
    sigma = [0.4] if channels == 1 else [0.2, 0.4, 0.8]
    return {"eta": 1.55, "sigma_a": sigma, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}


def python_eval(rows: int, runs: int, channels: int, threads: str | None) -> list[float]:
    env = dict(os.environ)
    if threads:
        env["RAYON_NUM_THREADS"] = threads
    out = subprocess.run([sys.executable, "-c", CHILD, str(rows), str(runs),
                          json.dumps(params(channels))], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def cli_eval(binary: Path, rows: int, runs: int, channels: int, threads: str | None,
             work: Path) -> list[float]:
    import numpy as np

    angles = work / "angles.csv"
    if not angles.exists():
        rng = np.random.default_rng(1)
        a = np.column_stack([rng.uniform(-85, 85, rows), rng.uniform(-180, 180, rows),
                             rng.uniform(-85, 85, rows), rng.uniform(-180, 180, rows)])
        with open(angles, "w") as f:
            f.write("theta_i,phi_i,theta_r,phi_r\n")
            for r in a.tolist():  # Python floats: repr is the shortest round-trip text
                f.write(f"{r[0]!r},{r[1]!r},{r[2]!r},{r[3]!r}\n")
    p = work / f"params{channels}.json"
    p.write_text(json.dumps(params(channels)))
    env = dict(os.environ)
    if threads:
        env["RAYON_NUM_THREADS"] = threads
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run([str(binary), "eval", "--params", str(p), "--input", str(angles),
                        "--output", "/dev/null"], env=env, check=True,
                       stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t)
    return times


def rust_bench() -> str:
    out = subprocess.run(["cargo", "bench", "--bench", "model", "--", "lanes/"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    lines = [l for l in out.splitlines() if l.startswith("lanes/") or "thrpt:" in l]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--rust-bench", action="store_true")
    args = ap.parse_args()
    binary = ROOT / "target" / "release" / "hairfit"
    subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "hairfit"], cwd=ROOT,
                   check=True)
    print(f"{args.rows} samples, median of {args.runs} runs, {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        for channels in (1, 3):
            for threads, label in (("1", "1 thread"), (None, "all cores")):
                py = statistics.median(python_eval(args.rows, args.runs, channels, threads))
                cli = statistics.median(cli_eval(binary, args.rows, args.runs, channels,
                                                 threads, Path(tmp)))
                print(f"{channels} ch, {label:9}: hairfit.eval {py:.3f} s "
                      f"({args.rows / py / 1e6:.2f} M samples/s); hairfit eval (CSV) "
                      f"{cli:.3f} s ({args.rows / cli / 1e6:.2f} M rows/s)")
    if args.rust_bench:
        print("cargo bench --bench model -- lanes/ (the model alone, one thread):")
        print(rust_bench())


if __name__ == "__main__":
    main()
