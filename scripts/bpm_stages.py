#!/usr/bin/env python3
"""The four compression stages of the densely arrayed bonded-particle model (DA-BPM) paper,
read from a run's series.csv (scenarios/compression_bpm_2d*.json), or its series.csv.part when
the run is still going or was stopped (a physical guard, a kill): what it reached so far.

The paper divides one-dimensional compression into four stages by the relative void ratio
e/e0 against the vertical stress (log scale) and the bond failures:
  I   no crushing: the specimen compacts elastically, e/e0 barely changes;
  II  crushing starts (first bond failures / first broken grains) with little volume change;
  III after the yield point: extensive crushing, e/e0 falls steeply (K0 0.2-0.4 while the
      relative void ratio is above about 0.3, then rising towards about 0.7);
  IV  fully crushed: e/e0 levels off, further crushing changes little.
Our copy of the paper gives no numerical boundaries, so this script places them by rules
stated here (ours): I/II at the first breakage event; II/III where the compression slope
-d(e/e0)/d(log10 stress), taken over half a decade around stress levels 8 per decade, first
reaches half of its largest value (not before I/II); III/IV where, after that largest value, the slope falls
below a quarter of it for good (not reached: the run ended in stage III).
The stress is the running maximum of the platen stress binned by axial strain (a strain-
controlled platen drops its stress at every crushing event; the envelope is the loading
curve). K0 is the mean of series.csv's k0 (lateral / axial wall stress) in each bin.

  scripts/bpm_stages.py OUT_DIR [--bin 0.005] [--at 1e6,5e6,...]
prints the table and the stages and writes OUT_DIR/bpm_stages.json.
"""
import argparse
import csv
import json
import math
import os
import sys


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--bin", type=float, default=0.005, help="axial strain per bin (default 0.005)")
    ap.add_argument("--at", default="1e6,2e6,5e6,10e6,20e6,50e6,100e6,150e6,200e6,300e6,400e6",
                    help="stresses (Pa) at which to report e, e/e0 and K0")
    a = ap.parse_args()
    path = os.path.join(a.out, "series.csv")
    if not os.path.exists(path) and os.path.exists(path + ".part"):
        path += ".part"
        print(f"bpm_stages: {path}: the run did not finish; its stages so far")
    if not os.path.exists(path):
        sys.exit(f"bpm_stages: {path} not found (nor series.csv.part)")
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    if len(rows) < 3:
        sys.exit(f"bpm_stages: {path} has fewer than 3 rows")
    bins = {}
    for r in rows:
        k = int(float(r["axial_strain"]) / a.bin)
        b = bins.setdefault(k, {"s": [], "e": [], "k0": [], "ev": 0, "strain": []})
        b["s"].append(float(r["platen_stress_Pa"]))
        b["e"].append(float(r["void_ratio"]))
        b["strain"].append(float(r["axial_strain"]))
        if r.get("k0", "") not in ("", None):
            k0 = float(r["k0"])
            if math.isfinite(k0) and 0 <= k0 < 10:
                b["k0"].append(k0)
        b["ev"] = max(b["ev"], int(float(r["breakage_events"])))
    e0 = float(rows[0]["void_ratio"])
    curve, env = [], 0.0
    for k in sorted(bins):
        b = bins[k]
        env = max(env, sum(b["s"]) / len(b["s"]))
        curve.append({"strain": sum(b["strain"]) / len(b["strain"]), "stress_Pa": env,
                      "e": sum(b["e"]) / len(b["e"]), "k0": (sum(b["k0"]) / len(b["k0"])) if b["k0"] else None,
                      "events": b["ev"]})
    for c in curve:
        c["e_rel"] = c["e"] / e0 if e0 > 0 else None
    # compression slope -d(e/e0)/d(log10 stress) at stress levels 8 per decade (the first e/e0
    # reached at or above each level), over half a decade: it smooths the envelope's sawtooth
    lo = next((c["stress_Pa"] for c in curve if c["stress_Pa"] > 0), None)
    levels_s, slopes = [], []
    if lo:
        k = 0
        while lo * 10 ** (k / 8) <= curve[-1]["stress_Pa"]:
            s_k = lo * 10 ** (k / 8)
            i = next(i for i, c in enumerate(curve) if c["stress_Pa"] >= s_k)
            levels_s.append((s_k, i))
            k += 1
        # slope at level j over the half decade [j - 2, j + 2] (clipped at the ends)
        for j in range(1, len(levels_s)):
            a0, a1 = max(0, j - 2), min(len(levels_s) - 1, j + 2)
            (s0, i0), (s1, i1) = levels_s[a0], levels_s[a1]
            slopes.append((j, -(curve[i1]["e_rel"] - curve[i0]["e_rel"]) / (math.log10(s1) - math.log10(s0))))
    stages = {"e0": e0}
    first = next((c for c in curve if c["events"] > 0), None)
    stages["I_to_II_Pa"] = first["stress_Pa"] if first else None
    if slopes:
        jmax, cmax = max(slopes, key=lambda t: t[1])
        s_first = stages["I_to_II_Pa"] or 0.0  # no yield before the first crushing
        jj = next((j for j, c in slopes if c >= 0.5 * cmax and levels_s[j - 1][0] >= s_first), jmax)
        stages["II_to_III_Pa"] = levels_s[jj - 1][0]
        after = [j for j, c in slopes if j > jmax and all(c2 < 0.25 * cmax for j2, c2 in slopes if j2 >= j)]
        stages["III_to_IV_Pa"] = levels_s[after[0] - 1][0] if after else None
        stages["max_slope"] = cmax
    levels = [float(x) for x in a.at.split(",") if x]
    table = []
    for s in levels:
        c = next((c for c in curve if c["stress_Pa"] >= s), None)
        if c:
            table.append({"stress_Pa": s, "e": c["e"], "e_rel": c["e_rel"], "k0": c["k0"], "events": c["events"],
                          "strain": c["strain"]})
    print(f"e0 = {e0:.4f}")
    print("stress_MPa  strain   e       e/e0    K0     events")
    for t in table:
        k0 = f"{t['k0']:.3f}" if t["k0"] is not None else "  -  "
        print(f"{t['stress_Pa'] / 1e6:9.1f}  {t['strain']:.4f}  {t['e']:.4f}  {t['e_rel']:.4f}  {k0}  {t['events']}")
    for key, name in (("I_to_II_Pa", "I -> II (first crushing)"), ("II_to_III_Pa", "II -> III (yield)"),
                      ("III_to_IV_Pa", "III -> IV (fully crushed)")):
        v = stages.get(key)
        print(f"{name}: " + (f"{v / 1e6:.1f} MPa" if v else "not reached"))
    json.dump({"stages": stages, "table": table, "curve": curve}, open(os.path.join(a.out, "bpm_stages.json"), "w"),
              indent=1)


if __name__ == "__main__":
    main()
