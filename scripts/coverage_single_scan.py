#!/usr/bin/env python3
"""Coverage of hairfit's 68%/95% intervals (profile and linearised) per parameter, over seeded
noisy datasets on one rig, fitted through the binary with default options and --intervals profile.

    python3 scripts/coverage_single_scan.py --rig azimuthal:incidences=30:steps=120 \
        --noise relative:0.1 --n 60 [--hairfit target/release/hairfit] [--params data/true_1ch.json]

A profile interval open on a side covers the truth on that side (it reaches the bound). The
linearised interval is value ± z·SE (z = 1 and 1.96); a parameter without an SE is counted apart.
Binomial 3-sigma band for a correct 68.27% interval over N trials: 0.6827 ± 3·sqrt(0.6827·0.3173/N).
"""
import argparse, json, math, os, subprocess, sys, tempfile

ap = argparse.ArgumentParser()
ap.add_argument("--rig", required=True)
ap.add_argument("--noise", default="relative:0.1")
ap.add_argument("--n", type=int, default=60)
ap.add_argument("--first-seed", type=int, default=100)
ap.add_argument("--hairfit", default="target/release/hairfit")
ap.add_argument("--params", default="data/true_1ch.json")
ap.add_argument("--fit-args", default="", help="extra fit options, space-separated")
a = ap.parse_args()

truth = json.load(open(a.params))
sigma_a = truth["sigma_a"]
truth_flat = {k: v for k, v in truth.items() if k != "sigma_a"}
truth_flat["sigma_a[0]"] = sigma_a[0] if isinstance(sigma_a, list) else sigma_a
truth_flat.setdefault("delta_eta_prime", 0.3)
truth_flat.setdefault("delta_h_m", 0.5)

stats = {}  # name -> counters
verdicts = {}
reasons_seen = {}
work = tempfile.mkdtemp(prefix="hairfit-cov-")
for k in range(a.n):
    seed = a.first_seed + k
    csv = os.path.join(work, f"d{seed}.csv")
    out = os.path.join(work, f"f{seed}")
    subprocess.run([a.hairfit, "synth", "--params", a.params, "--rig", a.rig, "--noise", a.noise,
                    "--seed", str(seed), "--output", csv], check=True, capture_output=True)
    r = subprocess.run([a.hairfit, "fit", csv, "--out", out, "--intervals", "profile", "--no-progress",
                        "--force"] + a.fit_args.split(), capture_output=True, text=True)
    fj = json.load(open(os.path.join(out, "fit.json")))
    verdicts[fj["verdict"]] = verdicts.get(fj["verdict"], 0) + 1
    for reason in fj.get("reasons", []):
        key = reason[:70]
        reasons_seen[key] = reasons_seen.get(key, 0) + 1
    for p in fj["parameters"]:
        if p["status"] == "fixed" or p["name"] not in truth_flat:
            continue
        t = truth_flat[p["name"]]
        s = stats.setdefault(p["name"], dict(n=0, p68=0, p95=0, nse=0, l68=0, l95=0, und=0, open=0, ps68=0))
        s["n"] += 1
        if p["status"] == "undetermined":
            s["und"] += 1
        def inside(iv):
            if iv is None:
                return None
            lo, hi = iv.get("lower"), iv.get("upper")
            return (lo is None or lo <= t) and (hi is None or t <= hi)
        i68, i95 = inside(p.get("interval_68")), inside(p.get("interval_95"))
        iv = p.get("interval_68") or {}
        if iv.get("lower") is None or iv.get("upper") is None:
            s["open"] += 1
        s["p68"] += bool(i68)
        s["p95"] += bool(i95)
        if p.get("std_error") is not None and p.get("value") is not None:
            se, v = p["std_error"], p["value"]
            s["nse"] += 1
            s["l68"] += abs(v - t) <= se
            s["l95"] += abs(v - t) <= 1.96 * se
            s["ps68"] += bool(i68)
    print(f"seed {seed}: {fj['verdict']}", file=sys.stderr)

print(f"rig {a.rig}, noise {a.noise}, {a.n} datasets, fit options: --intervals profile {a.fit_args}")
print(f"verdicts: {verdicts}")
print(f"{'parameter':<16}{'n':>4}{'undet':>6}{'open68':>7}{'prof68':>8}{'prof95':>8}{'n_se':>6}{'lin68':>8}{'lin95':>8}{'prof68|se':>10}")
tot = dict(n=0, p68=0, p95=0, nse=0, l68=0, l95=0, ps68=0)
for name, s in stats.items():
    r = lambda h, n: f"{h / n:.3f}" if n else "  -  "
    print(f"{name:<16}{s['n']:>4}{s['und']:>6}{s['open']:>7}{r(s['p68'], s['n']):>8}{r(s['p95'], s['n']):>8}"
          f"{s['nse']:>6}{r(s['l68'], s['nse']):>8}{r(s['l95'], s['nse']):>8}{r(s['ps68'], s['nse']):>10}")
    for k in tot:
        tot[k] += s[k]
half = lambda p, n: 3 * math.sqrt(p * (1 - p) / max(n, 1))
print(f"pooled: profile 68% {tot['p68'] / tot['n']:.3f} 95% {tot['p95'] / tot['n']:.3f} over {tot['n']}; "
      f"linearised 68% {tot['l68'] / max(tot['nse'], 1):.3f} 95% {tot['l95'] / max(tot['nse'], 1):.3f} over {tot['nse']} with an SE")
print(f"3-sigma band per parameter (n={a.n}): 68% ±{half(0.6827, a.n):.3f}, 95% ±{half(0.95, a.n):.3f}")
print("reasons (first 70 chars, count):")
for k, v in sorted(reasons_seen.items(), key=lambda kv: -kv[1])[:12]:
    print(f"  {v:>3}  {k}")
