#!/usr/bin/env python3
"""The three failure criteria of the stress model (Harmon et al. 2020, eqs. 7-10) on the quick
2D oedometer (scenarios/oedometer_harmon_2d_quick.json), side by side: platen stress against
axial strain, and the grain count against axial strain. The packing is settled once; the
three runs start from its packing.json, so they differ only in the criterion.

    PYTHONPATH=build/python python3 examples/python/criteria_2d.py --out out/criteria_2d

The full scenario strains to 15 % (about a minute of CPU per criterion); --stop-strain,
--strain-rate and --settle-time shorten it (the test suite runs it so, in seconds)."""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import crumble  # noqa: E402

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "oedometer_harmon_2d_quick.json"
CRITERIA = ("von_mises", "max_principal", "tresca")


def scenario(args, criterion):
    sc = crumble.Scenario.load(SCENARIO).set("breakage.criterion", criterion)
    if args.stop_strain is not None:
        sc.set("loading.stop_strain", args.stop_strain).set("output.psd_at_strain", [])
    if args.strain_rate is not None:
        sc.set("loading.strain_rate", args.strain_rate)
    if args.settle_time is not None:
        sc.set("packing.settle.max_time", args.settle_time)
    return sc


def run_criteria(out, args):
    """The packing settled once (as crumble compare does), then one run per criterion from it."""
    crumble.run(scenario(args, CRITERIA[0]), out=out / "packing", packing_only=True, force=True)
    packing = {"type": "file", "path": str(out / "packing" / "packing.json")}
    return {c: crumble.run(scenario(args, c).set("packing", packing), out=out / c, force=True) for c in CRITERIA}


def plot(runs, png):
    loading = next(iter(runs.values())).scenario["loading"]
    fig, (ax_s, ax_n) = plt.subplots(1, 2, figsize=(11, 4.2))
    for criterion, r in runs.items():
        s = r.series
        label = f"{criterion} ({r.summary['breakage_events']} breakage events)"
        ax_s.plot(100 * s["axial_strain"], s["platen_stress_Pa"] / 1e6, label=label)
        ax_n.plot(100 * s["axial_strain"], s["grains"], label=criterion)
    every = next(iter(runs.values())).scenario["simulation"]["sample_every"]
    ax_s.set(xlabel="axial strain (%)", ylabel="platen stress (MPa)",
             title=f"stress on the platen (series.csv: every {every} steps)")
    ax_n.set(xlabel="axial strain (%)", ylabel="grains in the cell", title="grain count (fragments included)")
    for ax in (ax_s, ax_n):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{SCENARIO.name}: the three criteria of the stress model, same packing, "
                 f"strain rate {loading['strain_rate']:g} /s")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("out/criteria_2d"))
    ap.add_argument("--stop-strain", type=float, help="end the loading at this axial strain (scenario: 0.15)")
    ap.add_argument("--strain-rate", type=float, help="loading.strain_rate, 1/s (scenario: 5)")
    ap.add_argument("--settle-time", type=float, help="packing.settle.max_time, s (scenario: 0.05)")
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    plot(run_criteria(a.out, a), a.out / "criteria_2d.png")
    print(a.out / "criteria_2d.png")


if __name__ == "__main__":
    main()
