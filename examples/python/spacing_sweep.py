#!/usr/bin/env python3
"""The single grain (scenarios/single_grain_pd.json, Zhu & Zhao 2019 §4.2) at several
peridynamics lattice spacings (breakage.spacing_fraction, spacing / grain diameter) with
crumble.sweep: left, the crushing force against the spacing; right, each setting's error
against the finest (the reference) over its wall time, the error-cost front joined.

    PYTHONPATH=build/python python3 examples/python/spacing_sweep.py --out out/spacing_sweep

The default values are the ones of studies/pd_spacing.json (a few minutes on 2 cores);
--values 0.15,0.12 is a quick look (the test suite runs that)."""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import crumble  # noqa: E402

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "single_grain_pd.json"


def plot(sw, png):
    t = sw.table.sort_values("breakage.spacing_fraction")
    ok = t[(t["status"] == "ok") & t["crushing_force_N"].notna()]
    unbroken = t[(t["status"] == "ok") & t["crushing_force_N"].isna()]["breakage.spacing_fraction"]
    failed = t[t["status"] != "ok"]["breakage.spacing_fraction"]
    ref = ok[ok["reference"] == 1]
    fig, (ax_f, ax_e) = plt.subplots(1, 2, figsize=(11, 4.2))
    ax_f.plot(ok["breakage.spacing_fraction"], ok["crushing_force_N"], "o-", label="setting")
    ax_f.plot(ref["breakage.spacing_fraction"], ref["crushing_force_N"], "k*", ms=12, label="reference (finest)")
    note = "".join(f"\n{v:g}: {what}" for vals, what in ((unbroken, "did not break"), (failed, "failed"))
                   for v in vals)
    ax_f.set(xlabel="lattice spacing / grain diameter", ylabel="crushing force (N)",
             title="crushing force of the 2 mm grain" + note)
    front = ok[ok["on_front"] == 1].sort_values("wall_seconds")
    ax_e.plot(ok["wall_seconds"], 100 * ok["error"], "o", label="setting")
    ax_e.plot(front["wall_seconds"], 100 * front["error"], "r-", label="error-cost front")
    for _, row in ok.iterrows():
        ax_e.annotate(f"{row['breakage.spacing_fraction']:g}", (row["wall_seconds"], 100 * row["error"]),
                      textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax_e.set(xlabel="wall time of the run (s)", ylabel="crushing force error against the reference (%)",
             title="error against cost (labels: spacing)")
    for ax in (ax_f, ax_e):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/spacing_sweep"))
    ap.add_argument("--values", default="0.15,0.12,0.1,0.08,0.062", help="spacing fractions, coarse to fine")
    a = ap.parse_args()
    values = [float(v) for v in a.values.split(",")]
    sw = crumble.sweep(SCENARIO, out=a.out / "sweep", params={"breakage.spacing_fraction": values},
                       metrics=["crushing_force"], sets={"output.vtk_final": False}, threads=1, force=True)
    plot(sw, a.out / "spacing_sweep.png")
    print(a.out / "spacing_sweep.png")


if __name__ == "__main__":
    main()
