"""hairfit.eval on 1M samples beside the Rust model's own rate (README, "Python package").

Times, on the same 1,000,000 random directions (|θ| ≤ 85°, all effects, cubic mode, 1 and 3
channels):

- the model alone (``cargo bench --bench eval_rate``: the same parameters, angles and 256-sample
  batches, one thread, from radians), into a new result each run as hairfit.eval returns one
  (the rate ``hairfit.eval`` is compared with), and into a buffer already written (the kernel
  alone, warm pages);
- ``hairfit.eval`` from NumPy arrays, one thread (RAYON_NUM_THREADS=1) and all cores, into a
  new result, and one thread into a re-used ``out=`` array (compared with the warm buffer);
- ``hairfit eval`` (the CLI, CSV text in and out: parsing and formatting included) on the same
  angles, one thread and all cores;
- with ``--rust-bench``, ``cargo bench --bench model -- lanes/`` (the model alone, one thread,
  criterion, on the bench's own parameters and 1024 directions), as the README's eval section
  measures it.

Each timing is the median of ``--runs`` runs (each in a fresh process for the thread setting);
the model's and ``hairfit.eval``'s also as CPU time (the process's), steadier than wall-clock
time on a machine shared with other work.

Usage (repository root, with the package installed): python python/bench_eval.py [--runs 5]
[--rows 1000000] [--rust-bench] [--no-cli]
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


def angles(rows: int):
    """The benchmark's directions (degrees): the same in every process."""
    import numpy as np

    rng = np.random.default_rng(1)
    return [rng.uniform(-85, 85, rows), rng.uniform(-180, 180, rows),
            rng.uniform(-85, 85, rows), rng.uniform(-180, 180, rows)]


CHILD = r"""
import json, sys, time
import hairfit
sys.path.insert(0, sys.argv[4])
from bench_eval import angles
rows, runs, params = int(sys.argv[1]), int(sys.argv[2]), json.loads(sys.argv[3])
reuse = sys.argv[5] == "out"
a = angles(rows)
hairfit.eval(params, *(x[:1000] for x in a))  # warm up
out = hairfit.eval(params, *a) if reuse else None  # its pages touched once
wall, cpu = [], []
for _ in range(runs):
    t, c = time.perf_counter(), time.process_time()
    s = hairfit.eval(params, *a, out=out)
    wall.append(time.perf_counter() - t)
    cpu.append(time.process_time() - c)
print(json.dumps({"wall": wall, "cpu": cpu}))
"""


def params(channels: int) -> dict:
    sigma = [0.4] if channels == 1 else [0.2, 0.4, 0.8]
    return {"eta": 1.55, "sigma_a": sigma, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
            "w_c_deg": 15, "eccentricity": 0.9}


def python_eval(rows: int, runs: int, channels: int, threads: str | None,
                reuse: bool = False) -> dict:
    env = dict(os.environ)
    # NumPy's OpenBLAS keeps worker threads spinning after a call; on 2 cores they take the
    # core hairfit.eval's thread needs (measured: 80% of the model's rate with them, 91%
    # without, 1 channel). hairfit uses no BLAS, so they are pinned to the calling thread.
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    if threads:
        env["RAYON_NUM_THREADS"] = threads
    out = subprocess.run([sys.executable, "-c", CHILD, str(rows), str(runs),
                          json.dumps(params(channels)), str(Path(__file__).parent),
                          "out" if reuse else "new"], env=env,
                         check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out)


def cli_eval(binary: Path, rows: int, runs: int, channels: int, threads: str | None,
             work: Path) -> list[float]:
    import numpy as np

    csv = work / "angles.csv"
    if not csv.exists():
        a = np.column_stack(angles(rows))
        with open(csv, "w") as f:
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
        subprocess.run([str(binary), "eval", "--params", str(p), "--input", str(csv),
                        "--output", "/dev/null"], env=env, check=True,
                       stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t)
    return times


def model_rate(rows: int, runs: int, channels: int, work: Path) -> dict:
    """The model alone on the same angles, one thread (benches/eval_rate.rs)."""
    import numpy as np

    raw = work / "angles.f64"
    if not raw.exists():
        np.stack(angles(rows)).astype("<f8").tofile(raw)
    p = work / f"params{channels}.json"
    p.write_text(json.dumps(params(channels)))
    out = subprocess.run(["cargo", "bench", "--quiet", "--bench", "eval_rate", "--", str(raw),
                          str(p), str(runs)], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def rust_bench() -> str:
    out = subprocess.run(["cargo", "bench", "--bench", "model", "--", "lanes/"], cwd=ROOT,
                         capture_output=True, text=True, check=True).stdout
    lines = [l for l in out.splitlines() if l.startswith("lanes/") or "thrpt:" in l]
    return "\n".join(lines)


def median(times: dict) -> tuple[float, float]:
    """Median wall-clock and CPU time of the runs."""
    return statistics.median(times["wall"]), statistics.median(times["cpu"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--rust-bench", action="store_true")
    ap.add_argument("--no-cli", action="store_true", help="skip the CLI's timings")
    args = ap.parse_args()
    binary = ROOT / "target" / "release" / "hairfit"
    if not args.no_cli:
        subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "hairfit"], cwd=ROOT,
                       check=True)
    print(f"{args.rows} samples, median of {args.runs} runs, {os.cpu_count()} cores; "
          "wall-clock time (CPU time)")
    rate = lambda t: f"{args.rows / t / 1e6:.2f}"  # noqa: E731
    with tempfile.TemporaryDirectory() as tmp:
        for channels in (1, 3):
            times = model_rate(args.rows, args.runs, channels, Path(tmp))
            kernel, kernel_cpu = median(times)
            print(f"{channels} ch, the model alone into a warm buffer, 1 thread: {kernel:.3f} s "
                  f"({kernel_cpu:.3f} s): {rate(kernel)} ({rate(kernel_cpu)}) M samples/s")
            model, model_cpu = median({"wall": times["fresh_wall"], "cpu": times["fresh_cpu"]})
            print(f"{channels} ch, the model alone into a new result, 1 thread: {model:.3f} s "
                  f"({model_cpu:.3f} s): {rate(model)} ({rate(model_cpu)}) M samples/s")
            for threads, label in (("1", "1 thread"), (None, "all cores")):
                py, py_cpu = median(python_eval(args.rows, args.runs, channels, threads))
                ratio = (f", {model / py:.0%} ({model_cpu / py_cpu:.0%}) of the model's rate "
                         f"into a new result, {kernel / py:.0%} of its warm-buffer rate"
                         if threads == "1" else "")
                print(f"{channels} ch, {label:9}: hairfit.eval {py:.3f} s ({py_cpu:.3f} s): "
                      f"{rate(py)} ({rate(py_cpu)}) M samples/s{ratio}")
                if threads == "1":
                    pyo, pyo_cpu = median(python_eval(args.rows, args.runs, channels, threads,
                                                      reuse=True))
                    print(f"{channels} ch, {label:9}: hairfit.eval(out=) {pyo:.3f} s "
                          f"({pyo_cpu:.3f} s): {rate(pyo)} ({rate(pyo_cpu)}) M samples/s, "
                          f"{kernel / pyo:.0%} ({kernel_cpu / pyo_cpu:.0%}) of the model's "
                          "warm-buffer rate")
                if not args.no_cli:
                    cli = statistics.median(cli_eval(binary, args.rows, args.runs, channels,
                                                     threads, Path(tmp)))
                    print(f"{channels} ch, {label:9}: hairfit eval (CSV) {cli:.3f} s: "
                          f"{rate(cli)} M rows/s")
    if args.rust_bench:
        print("cargo bench --bench model -- lanes/ (the model alone, one thread):")
        print(rust_bench())


if __name__ == "__main__":
    main()
