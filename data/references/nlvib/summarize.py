#!/usr/bin/env python3
"""Tabulate NLvib-py's harmonic-balance branches against the exact shooting reference.

Reads the CSV files written by ``run_sdof_unilateral.py`` (NLvib-py) and ``shooting_scipy.py``
(independent shooting) in --dir and writes

* ``convergence.csv``: for each harmonic truncation H, the largest-frequency turning point (the
  fold of the hardening branch) and the first-harmonic amplitude at fixed frequencies on the
  stable (resonant) and the unstable (overhanging) part of the branch, each beside the shooting
  value and the difference. The shooting orbits have no truncation, so the differences are
  NLvib's harmonic-truncation (and AFT sampling) error.
* ``stability_agreement.csv``: how often NLvib-py's stability verdicts agree with the exact
  ones, by part of the branch. The exact shooting finds the resonant part (up to the fold)
  stable, the overhang (from the fold down to the lower turning point) unstable and the
  non-impacting part beyond it stable; every NLvib point is classified by the part it lies on.

Needs only the Python standard library and numpy.
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

# Frequencies (rad/s) at which the amplitude of each branch part is compared (where a part
# does not reach a frequency, for instance beyond a low truncation's fold, no row is written).
PROBE_OMEGAS = (1.1, 1.2, 1.3, 1.4, 1.5)


def read(path: Path) -> dict[str, np.ndarray]:
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    out = {}
    for key in rows[0]:
        try:
            out[key] = np.array([float(r[key]) for r in rows])
        except ValueError:
            out[key] = np.array([r[key] for r in rows])
    return out


def interp_at(omega, values, idx, w):
    o, v = omega[idx], values[idx]
    order = np.argsort(o)
    o, v = o[order], v[order]
    if not (o[0] <= w <= o[-1]):
        return float("nan")
    return float(np.interp(w, o, v))


def write(path: Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})


def part_of(point: int, i_top: int, i_low: int) -> str:
    if point <= i_top:
        return "resonant"
    if point <= i_low:
        return "overhang"
    return "non_impacting"


EXACT_STABLE = {"resonant": True, "overhang": False, "non_impacting": True}


def stability_rows(d: Path, shoot, nl_folds, harm, parts) -> list[dict]:
    """Agreement of NLvib-py's stability verdicts with the exact ones, by branch part."""
    # The exact verdicts by part, checked on the shooting branch itself.
    seg0 = shoot["segment"] == 0
    i_top = int(np.argmax(shoot["omega_rad_s"][seg0]))
    st = shoot["stable"][seg0] == "true"
    # (one point of slack at the fold, where the verdict changes)
    assert st[:i_top].all() and not st[i_top + 2:].any(), "exact verdicts changed"
    assert (shoot["stable"][~seg0] == "true").all(), "exact verdicts changed"

    out = []

    def tally(method, points, stable, H):
        i_top, i_low = parts[H]
        for part in ("resonant", "overhang", "non_impacting"):
            sel = np.array([part_of(int(p), i_top, i_low) == part for p in points])
            n = int(sel.sum())
            if n == 0:
                continue
            agree = int((stable[sel] == EXACT_STABLE[part]).sum())
            out.append({"method": method, "branch_part": part,
                        "exact_stable": str(EXACT_STABLE[part]).lower(), "points": n,
                        "agree": agree, "disagree": n - agree})

    for H in sorted(parts):
        hb = read(d / f"nlvib_hb_H{H:02d}.csv")
        stable = hb["nlvib_unstable_between_folds"] == "false"
        tally(f"nlvib_hb_H{H}_fold_parity_flag", hb["point"], stable, H)
    for f in sorted(d.glob("nlvib_shooting_N*.csv")):
        sh = read(f)
        ok = sh["converged"] == "true"
        tally(f"{f.stem}_floquet", sh["hb_point"][ok], sh["stable"][ok] == "true", max(parts))
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--dir", type=Path, default=Path(__file__).resolve().parent)
    args = p.parse_args(argv)
    d = args.dir

    shoot = read(d / "shooting_branch.csv")
    shoot_folds = read(d / "shooting_folds.csv")
    nl_folds = read(d / "nlvib_folds.csv")
    i_fold = np.flatnonzero(shoot_folds["kind"] == "fold_max_omega")[0]
    ref_fold_om = shoot_folds["omega_rad_s"][i_fold]
    ref_fold_a1 = shoot_folds["a1_amplitude_m"][i_fold]
    # Shooting segment 0 runs from the lowest frequency over the fold down the overhang to
    # the grazing orbit: split it at its largest frequency.
    seg0 = shoot["segment"] == 0
    s_om, s_a1 = shoot["omega_rad_s"][seg0], shoot["a1_amplitude_m"][seg0]
    i_top = int(np.argmax(s_om))
    s_res, s_over = np.arange(0, i_top + 1), np.arange(i_top, len(s_om))

    harm = np.array([float(x) if str(x) else np.nan for x in nl_folds["harmonics_H"]])
    rows = []
    parts = {}
    hb_files = sorted(d.glob("nlvib_hb_H*.csv"))
    for f in hb_files:
        hb = read(f)
        H = int(f.stem.split("_H")[1])
        om, a1 = hb["omega_rad_s"], hb["a1_amplitude_m"]
        sel = (nl_folds["source"] == "nlvib_hb") & (harm == H) & (
            nl_folds["kind"] == "fold_max_omega")
        # The fold of the hardening branch is the turning point of largest frequency.
        k = np.flatnonzero(sel)[np.argmax(nl_folds["omega_rad_s"][sel])]
        fold_om, fold_a1 = nl_folds["omega_rad_s"][k], nl_folds["a1_amplitude_m"][k]
        rows.append({"harmonics_H": H, "quantity": "fold_omega_rad_s", "omega_rad_s": "",
                     "nlvib": fold_om, "shooting": ref_fold_om, "nlvib_minus_shooting":
                     fold_om - ref_fold_om})
        rows.append({"harmonics_H": H, "quantity": "fold_a1_amplitude_m", "omega_rad_s": "",
                     "nlvib": fold_a1, "shooting": ref_fold_a1, "nlvib_minus_shooting":
                     fold_a1 - ref_fold_a1})
        # Resonant part: up to the fold; overhang: from the fold to the lower turning point.
        i_top = int(nl_folds["point"][k])
        later = (nl_folds["source"] == "nlvib_hb") & (harm == H) & (
            nl_folds["kind"] == "fold_min_omega") & (nl_folds["point"] > i_top)
        # (the lower turning point is the one of least frequency: near the fold, a sampled
        # contact force also makes micro turning points, see PROVENANCE.md)
        i_low = (int(nl_folds["point"][later][np.argmin(nl_folds["omega_rad_s"][later])])
                 if np.any(later) else len(om) - 1)
        h_res, h_over = np.arange(0, i_top + 1), np.arange(i_top, i_low + 1)
        parts[H] = (i_top, i_low)
        for part, hi, si in (("resonant", h_res, s_res), ("overhang", h_over, s_over)):
            for w in PROBE_OMEGAS:
                a_h = interp_at(om, a1, hi, w)
                a_s = interp_at(s_om, s_a1, si, w)
                if np.isnan(a_h) or np.isnan(a_s):
                    continue
                rows.append({"harmonics_H": H, "quantity": f"a1_amplitude_m_{part}",
                             "omega_rad_s": w, "nlvib": a_h, "shooting": a_s,
                             "nlvib_minus_shooting": a_h - a_s})

    write(d / "convergence.csv", rows)
    write(d / "stability_agreement.csv", stability_rows(d, shoot, nl_folds, harm, parts))
    for r in rows:
        if r["quantity"].startswith("fold"):
            print(f"H={r['harmonics_H']:>2} {r['quantity']:<20} nlvib={r['nlvib']:.6f} "
                  f"shooting={r['shooting']:.6f} diff={r['nlvib_minus_shooting']:+.2e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
