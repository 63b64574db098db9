#!/usr/bin/env python3
"""Largest differences between two fit directories' fit.json (or two compare directories):
each parameter's value in units of its standard error, each 68% interval end in units of the
interval's width, and whether the verdicts agree. Used to check that a speed change keeps the
same answers (the bar: values within SE/100, intervals within 1% of their width).

Usage: scripts/fit_diff.py OLD_DIR NEW_DIR   (fit directories, or compare directories: then
every family sub-directory present in both)."""
import json
import os
import sys


def fits(d):
    if os.path.exists(os.path.join(d, "fit.json")):
        return {"": d}
    return {n: os.path.join(d, n) for n in sorted(os.listdir(d))
            if os.path.exists(os.path.join(d, n, "fit.json"))}


def diff(a, b):
    ja, jb = (json.load(open(os.path.join(x, "fit.json"))) for x in (a, b))
    worst_se, worst_iv = 0.0, 0.0
    pb = {p["name"]: p for p in jb["parameters"]}
    for p in ja["parameters"]:
        q = pb[p["name"]]
        se = p.get("std_error") or 0.0
        if se > 0:
            worst_se = max(worst_se, abs(p["value"] - q["value"]) / se)
        ia, ib = p.get("interval_68"), q.get("interval_68")
        if ia and ib:
            width = ia["upper"] - ia["lower"]
            if width > 0:
                for end in ("lower", "upper"):
                    worst_iv = max(worst_iv, abs(ia[end] - ib[end]) / width)
    return ja["verdict"], jb["verdict"], worst_se, worst_iv


def main():
    old, new = sys.argv[1:3]
    fo, fn = fits(old), fits(new)
    bad = False
    print(f"{'fit':<12} {'verdicts':<22} {'max |Δvalue|/SE':>16} {'max |Δend|/width68':>19}")
    for name in fo:
        if name not in fn:
            continue
        va, vb, se, iv = diff(fo[name], fn[name])
        bad |= va != vb or se > 0.01 or iv > 0.01
        print(f"{name or '.':<12} {va + ' / ' + vb:<22} {se:>16.2e} {iv:>19.2e}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
