#!/usr/bin/env python3
"""Compare a run of scenarios/oedometer_zhu_zhao.json with Zhu & Zhao 2019 §5 (Figs. 12-18).

    python3 scripts/zz-validation.py RUN_DIR [RUN_DIR2]

Reads the run's series.csv, events.csv and the grain snapshots vtk/grains_*.vtp (the ".part"
files of a run still going, too) and prints, as Markdown tables:
  - per MPa of vertical stress: breakage events (analyses ending in a split), grains and void
    ratio at the end of the MPa; the paper: no crushing below 3 MPa, tens to about a hundred per
    MPa from 4 to 10 MPa, 500-600 per MPa above 20 MPa, about 27 400 grains at 30 MPa (Figs. 12-13);
  - the slope of the NCL in log10 e - log10 sigma over the reached part above 10 MPa and above
    the yield the paper names (6-8 MPa); the paper: about 0.52 (Fig. 12);
  - per grain snapshot: fractal dimension by number, N(d > d0) ~ d0^-D (eq. 17, fitted as
    crumble's core/Measures fractal_dimension does: 12 geometric sieves between the smallest and
    largest grain, sieves retaining fewer than max(10, n/1000) grains left out), and the share of
    grains with Zingg EI and FI both in [0.5, 1] and of crushed ones (generation > 0); the paper:
    D rises to about 2.3 (Fig. 17), EI and FI mostly 0.5-1.0 (Fig. 18).
With two run folders (two seeds) the per-MPa table shows both side by side.
Only the Python standard library is used.
"""
import csv
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

from crumble_plot import vtk_array_values  # scripts/crumble_plot.py, beside this script


def read_csv(run, name):
    for f in (name, name + ".part"):
        p = os.path.join(run, f)
        if os.path.exists(p):
            with open(p, newline="") as fh:
                return list(csv.DictReader(fh))
    sys.exit(f"zz-validation: {run} has no {name} (nor {name}.part)")


def events_per_mpa(run):
    ev = read_csv(run, "events.csv")
    out = {}
    for r in ev:
        if r["outcome"] == "split":
            k = int(float(r["platen_stress_Pa"]) // 1e6)
            out[k] = out.get(k, 0) + 1
    return out


def series(run):
    return [(float(r["target_stress_Pa"]), float(r["platen_stress_Pa"]), float(r["void_ratio"]), int(r["grains"]),
             int(r["step"])) for r in read_csv(run, "series.csv")]


def at_mpa(ser):
    """grains and e at the last sample of each MPa of commanded stress."""
    out = {}
    for target, _, e, n, _ in ser:
        out[int(target // 1e6)] = (n, e)
    return out


def ncl_slope(ser, lo):
    pts = [(math.log10(s), math.log10(e)) for _, s, e, _, _ in ser if s >= lo and e > 0]
    if len(pts) < 3:
        return float("nan"), 0
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    sxy = sum((p[0] - mx) * (p[1] - my) for p in pts)
    return (sxy / sxx if sxx > 0 else float("nan")), len(pts)


def fractal_dimension(d, sieves=12):
    if len(d) < 2 or max(d) <= min(d):
        return float("nan")
    lo, hi = min(d), max(d)
    xs, ys = [], []
    for k in range(sieves):
        s = lo * (hi / lo) ** ((k + 0.5) / sieves)
        n = sum(1 for v in d if v > s)
        if n < max(10, len(d) // 1000):
            continue
        xs.append(math.log10(s))
        ys.append(math.log10(n))
    if len(xs) < 2:
        return float("nan")
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    return -sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx


def snapshot(path):
    """per grain (id -> diameter, EI, FI, generation) from a grains_*.vtp (cell data per face)."""
    arrays = {}
    root = ET.parse(path).getroot()
    for el in root.iter("DataArray"):
        if el.get("Name") in ("grain", "diameter", "zingg_ei", "zingg_fi", "generation"):
            values = vtk_array_values(el, root)
            if values is None:
                sys.exit(f"zz-validation: {path}: DataArray {el.get('Name')} is in an encoding crumble does not write")
            arrays[el.get("Name")] = values
    grains = {}
    for i, g in enumerate(arrays.get("grain", [])):
        grains.setdefault(int(g), (arrays["diameter"][i], arrays["zingg_ei"][i], arrays["zingg_fi"][i],
                                   arrays.get("generation", [0] * (i + 1))[i]))
    return grains


def main():
    runs = sys.argv[1:]
    if not runs or len(runs) > 2:
        sys.exit(__doc__)
    sers = [series(r) for r in runs]
    evs = [events_per_mpa(r) for r in runs]
    ats = [at_mpa(s) for s in sers]
    top = max(max(a) for a in ats)
    head = "| MPa | paper: events/MPa |" + "".join(f" events ({os.path.basename(r.rstrip('/'))}) | grains | e |" for r in runs)
    print(head)
    print("|---|---|" + "---|---|---|" * len(runs))
    for k in range(0, top + 1):
        paper = "0" if k < 3 else ("tens to ~100" if 4 <= k < 10 else ("500-600" if k >= 20 else ""))
        row = f"| {k}-{k + 1} | {paper} |"
        for ev, at in zip(evs, ats):
            n, e = at.get(k, (None, None))
            row += f" {ev.get(k, 0)} | {n if n is not None else ''} | {e:.4f} |" if e is not None else f" {ev.get(k, 0)} | | |"
        print(row)
    print()
    for r, s in zip(runs, sers):
        e0 = s[0][2]
        print(f"{r}: e at the first sample {e0:.4f} (paper ≈ 0.71); reached {s[-1][0] / 1e6:.2f} MPa, "
              f"{s[-1][3]} grains (paper at 30 MPa ≈ 27 400)")
        for lo in (6e6, 10e6):
            b, n = ncl_slope(s, lo)
            print(f"  NCL slope d log10 e / d log10 sigma above {lo / 1e6:.0f} MPa: {b:.3f} over {n} samples (paper ≈ -0.52)")
        pvd = os.path.join(r, "grains.pvd")
        snaps = []
        if os.path.exists(pvd):
            for m in re.finditer(r'timestep="([^"]+)"[^>]*file="([^"]+)"', open(pvd).read()):
                snaps.append((float(m.group(1)), os.path.join(r, m.group(2))))
        steps = {int(st): (t, sg) for t, sg, _, _, st in s}
        print("\n| snapshot | step | MPa (commanded) | grains | D (eq. 17, by number) | EI and FI in [0.5, 1] | the same, crushed grains |")
        print("|---|---|---|---|---|---|---|")
        for t, f in snaps:
            if not os.path.exists(f):
                continue
            g = snapshot(f)
            step = int(re.search(r"(\d+)\.vtp$", f).group(1))
            mpa = 0.0 if step == 0 else steps.get(step, (float("nan"),))[0] / 1e6
            vals = list(g.values())
            inside = lambda v: 0.5 <= v[1] <= 1 and 0.5 <= v[2] <= 1
            crushed = [v for v in vals if v[3] > 0]
            share = sum(1 for v in vals if inside(v)) / max(1, len(vals))
            cshare = (f"{sum(1 for v in crushed if inside(v)) / len(crushed):.0%} of {len(crushed)}" if crushed else "–")
            print(f"| {os.path.basename(f)} | {step} | {mpa:.2f} | {len(vals)} | "
                  f"{fractal_dimension([v[0] for v in vals]):.2f} | {share:.0%} | {cshare} |")
        print()


if __name__ == "__main__":
    main()
