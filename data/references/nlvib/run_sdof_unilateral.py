#!/usr/bin/env python3
"""Frequency response of a one-sided spring oscillator computed with NLvib-py (peer reference).

Computes, with the harmonic balance, alternating frequency-time scheme and pseudo-arclength
continuation of NLvib-py (the Python port of NLvib, github.com/julianjurai/NLvib-py), the
period-one branch of

    m q'' + d q' + k q + kc * max(q - gap, 0) = F cos(Omega t)

(NLvib's ``SingleMassOscillator`` plus ``unilateral_spring``; the forcing is NLvib's cosine
fundamental-harmonic excitation) for several harmonic truncations H, and writes one CSV per H
and a table of the branch's turning points.

NLvib is GPL-3.0 and NLvib-py is its port; neither is part of this repository (it is not
vendored): this script only imports NLvib-py from an outside checkout (``--nlvib-src``, the
``src`` directory of NLvib-py at the commit named in PROVENANCE.md) and contains none of its
code.

What NLvib-py gives and what this script adds
---------------------------------------------
* Harmonic balance (``nlvib_hb_HNN.csv``, one per H): NLvib-py's branch points, the Fourier
  coefficients Q = [Q0, Qc1, Qs1, ..., QcH, QsH] of
  q(t) = Q0 + sum_h Qch cos(h Omega t) + Qsh sin(h Omega t), and Omega, with its stability
  flag. NLvib-py's harmonic-balance continuation has no Hill or Floquet analysis: the flag
  toggles whenever the tangent's Omega component changes sign (points between two turning
  points are "potentially unstable"). It is stored as it is.
  Added here from the coefficients only: the first-harmonic amplitude sqrt(Qc1^2 + Qs1^2)
  (what NLvib's example 03 plots), the extreme displacements of the truncated series over a
  period, the arclength along the branch in NLvib-py's own norm (Euclidean in [Q; Omega], the
  one its arclength constraint uses) and the turning points (``nlvib_folds.csv``: where
  Omega is extremal along the arclength, a parabola through the extremal point and its two
  neighbours, omega(s), a1(s), ..., evaluated at the vertex).
* Shooting and Floquet multipliers (``nlvib_shooting_NNNNN.csv``), as NLvib's example 03
  judges stability: NLvib-py's ``shooting_residual`` (Newmark, average acceleration, N steps
  per period; it returns R = y(T) - y(0) and J = Phi - I) is solved by Newton at fixed
  frequency from the harmonic-balance orbit of the largest H at every n-th branch point near
  or in contact and at the points next to each turning point; the multipliers are the
  eigenvalues of J + I. The first harmonic of the Newmark orbit is 2 |fft(q)[1]| / N over
  its N samples (as example 03 computes it).
* AFT sampling check (``nlvib_aft_check_HNN.csv``): every n-th impacting point of the largest
  H re-solved by Newton at its own frequency with four times the AFT samples.

Run (see PROVENANCE.md for the exact command that produced the stored files)::

    python run_sdof_unilateral.py --nlvib-src /work/peer/NLvib-py/src --out-dir .
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nlvib-src", type=Path, default=Path("/work/peer/NLvib-py/src"),
                   help="the src directory of an NLvib-py checkout (holds the nlvib package)")
    p.add_argument("--harmonics", default="1,3,5,10,20,40",
                   help="comma-separated harmonic truncations H")
    p.add_argument("--m", type=float, default=1.0)
    p.add_argument("--d", type=float, default=0.03)
    p.add_argument("--k", type=float, default=1.0)
    p.add_argument("--kc", type=float, default=100.0, help="contact stiffness")
    p.add_argument("--gap", type=float, default=1.0)
    p.add_argument("--force", type=float, default=0.1, help="amplitude of F cos(Omega t)")
    p.add_argument("--omega-start", type=float, default=0.5)
    p.add_argument("--omega-end", type=float, default=2.5)
    p.add_argument("--n-time", type=int, default=4096,
                   help="AFT time samples per period (NLvib-py's n_time)")
    p.add_argument("--newton-tol", type=float, default=1e-9)
    p.add_argument("--ds-initial", type=float, default=0.01)
    p.add_argument("--ds-max", type=float, default=0.02)
    p.add_argument("--ds-min", type=float, default=1e-7)
    p.add_argument("--max-steps", type=int, default=5000)
    p.add_argument("--samples-xmax", type=int, default=1 << 14,
                   help="phase samples on which the truncated series' maximum is taken")
    p.add_argument("--shooting-steps", type=int, default=4096,
                   help="Newmark steps per period for NLvib-py's shooting (0: no shooting)")
    p.add_argument("--shooting-every", type=int, default=4,
                   help="shoot from every n-th harmonic-balance point of the largest H whose "
                        "orbit comes within 0.1 of the gap (and from the points next to folds)")
    p.add_argument("--aft-check-every", type=int, default=10,
                   help="re-solve every n-th impacting point of the largest H with 4 n_time "
                        "AFT samples (0: no check)")
    p.add_argument("--out-dir", type=Path, default=Path("."))
    return p.parse_args(argv)


def source_digest(src: Path) -> str:
    """SHA-256 over NLvib-py's package sources (sorted paths and contents)."""
    h = hashlib.sha256()
    for f in sorted((src / "nlvib").rglob("*.py")):
        h.update(str(f.relative_to(src)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def fmt(v) -> str:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:.12g}"
    return str(v)


def write_csv(path: Path, columns: dict) -> None:
    """Write equally long columns (name -> sequence) as a CSV file."""
    names = list(columns)
    n = len(columns[names[0]])
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for i in range(n):
            w.writerow([fmt(columns[c][i]) for c in names])


def turning_points(arclength, omega, series: dict, label: dict) -> list[dict]:
    """Interior extrema of omega along the branch.

    A parabola through the extremal point and its two neighbours, omega(s), gives the vertex
    s*; each series (a1, mean, ...) is interpolated by a parabola in s at s*.
    """
    rows = []
    for i in range(1, len(omega) - 1):
        up = omega[i] - omega[i - 1]
        down = omega[i + 1] - omega[i]
        if up * down >= 0.0:
            continue
        s3 = arclength[i - 1:i + 2]
        c_om = np.polyfit(s3, omega[i - 1:i + 2], 2)
        s_star = -c_om[1] / (2.0 * c_om[0])
        row = dict(label)
        row["kind"] = "fold_max_omega" if up > 0 else "fold_min_omega"
        row["omega_rad_s"] = float(np.polyval(c_om, s_star))
        for name, values in series.items():
            row[name] = float(np.polyval(np.polyfit(s3, values[i - 1:i + 2], 2), s_star))
        row["omega_extreme_point_rad_s"] = float(omega[i])
        row["neighbour_spacing_arclength"] = float(max(s3[1] - s3[0], s3[2] - s3[1]))
        row["point"] = i
        rows.append(row)
    return rows


def continuation_options(args, ContinuationOptions):
    return ContinuationOptions(
        ds_initial=args.ds_initial,
        ds_min=args.ds_min,
        ds_max=args.ds_max,
        max_steps=args.max_steps,
        max_newton_iter=25,
        newton_tol=args.newton_tol,
        adapt_step=True,
        lambda_min=args.omega_start - 0.1 * (args.omega_end - args.omega_start),
        lambda_max=args.omega_end,
    )


def main(argv=None) -> int:
    args = parse_args(argv)
    src = args.nlvib_src.resolve()
    if not (src / "nlvib" / "__init__.py").is_file():
        print(f"error: no nlvib package under --nlvib-src {src}", file=sys.stderr)
        return 2
    sys.path.insert(0, str(src))

    import scipy

    import nlvib
    from nlvib.continuation.solver import ContinuationOptions, ContinuationSolver
    from nlvib.nonlinearities.elements import unilateral_spring
    from nlvib.solvers.harmonic_balance import hb_residual
    from nlvib.solvers.shooting import newmark_step, shooting_residual
    from nlvib.systems.oscillators import SingleMassOscillator

    if not Path(nlvib.__file__).resolve().is_relative_to(src):
        print(f"error: nlvib imported from {nlvib.__file__}, not {src}", file=sys.stderr)
        return 2

    system = SingleMassOscillator(m=args.m, d=args.d, k=args.k)
    system.add_nonlinear_element(unilateral_spring(k=args.kc, gap=args.gap, dof_index=0))
    excitation = {"dof": 0, "amplitude": args.force}
    harmonics = [int(h) for h in args.harmonics.split(",") if h]
    args.out_dir.mkdir(parents=True, exist_ok=True)

    fold_rows = []
    runs = []
    last_hb = None
    for H in harmonics:
        n_time = args.n_time

        def residual(Q, omega, H=H, n_time=n_time):
            return hb_residual(Q, omega, system, H, excitation, n_time=n_time)

        # Start: Newton at the lowest frequency from rest (the orbit there does not reach
        # the gap, so it is the linear one).
        Q0 = np.zeros(2 * H + 1)
        for _ in range(50):
            R, J = residual(Q0, args.omega_start)
            if np.linalg.norm(R) < args.newton_tol:
                break
            Q0 = Q0 + np.linalg.solve(J, -R)
        else:
            raise RuntimeError(f"H={H}: no start solution at omega={args.omega_start}")

        t0 = time.perf_counter()
        result = ContinuationSolver().run(residual, Q0, args.omega_start,
                                          continuation_options(args, ContinuationOptions))
        wall = time.perf_counter() - t0
        print(f"H={H}: {result.n_steps} points, {result.message}, {wall:.1f} s", file=sys.stderr)
        if not result.converged:
            print(f"warning: H={H}: the continuation stopped early: {result.message}",
                  file=sys.stderr)

        sol = result.solutions
        Q = sol[:, :-1]
        omega = sol[:, -1]
        arclength = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(sol, axis=0), axis=1))])
        a1 = np.hypot(Q[:, 1], Q[:, 2])
        mean = Q[:, 0]
        # Largest and smallest displacement of the truncated series over one period.
        phase = 2.0 * math.pi * np.arange(args.samples_xmax) / args.samples_xmax
        hh = np.arange(1, H + 1)
        q_t = mean[:, None] + Q[:, 1::2] @ np.cos(np.outer(hh, phase)) \
            + Q[:, 2::2] @ np.sin(np.outer(hh, phase))
        x_max = q_t.max(axis=1)
        x_min = q_t.min(axis=1)
        flag = np.asarray(result.stability, dtype=bool)
        write_csv(args.out_dir / f"nlvib_hb_H{H:02d}.csv", {
            "point": list(range(len(omega))),
            "arclength": list(map(float, arclength)),
            "omega_rad_s": list(map(float, omega)),
            "a1_amplitude_m": list(map(float, a1)),
            "a1_cos_m": list(map(float, Q[:, 1])),
            "a1_sin_m": list(map(float, Q[:, 2])),
            "mean_m": list(map(float, mean)),
            "x_max_m": list(map(float, x_max)),
            "x_min_m": list(map(float, x_min)),
            "nlvib_unstable_between_folds": [bool(f) for f in flag],
        })
        fold_rows += turning_points(
            arclength, omega, {"a1_amplitude_m": a1, "mean_m": mean, "x_max_m": x_max},
            {"source": "nlvib_hb", "harmonics_H": H})
        runs.append(("hb", H, result.n_steps, wall, result.message))
        if last_hb is None or H > last_hb[0]:
            last_hb = (H, Q, omega, a1, x_max)

    if args.aft_check_every > 0:
        # The AFT samples the contact force at n_time phases; re-solve every n-th point of the
        # largest H at its own frequency with four times as many samples to show how much of
        # the remaining difference to exact orbits is sampling rather than truncation.
        H, Q_hb, omega_hb, a1_hb, x_max_hb = last_hb
        n_fine = 4 * args.n_time
        near_fold = {j for r in fold_rows if r["source"] == "nlvib_hb" and r["harmonics_H"] == H
                     for j in range(r["point"] - 3, r["point"] + 4)}
        cols = {k: [] for k in ("hb_point", "omega_rad_s", "a1_amplitude_m",
                                "a1_amplitude_m_fine", "mean_m", "mean_m_fine",
                                "residual_norm_fine")}
        for i in range(0, len(omega_hb), args.aft_check_every):
            if i in near_fold or x_max_hb[i] <= args.gap:
                continue
            om = float(omega_hb[i])
            Qf = Q_hb[i].copy()
            for _ in range(30):
                R, J = hb_residual(Qf, om, system, H, excitation, n_time=n_fine)
                if np.linalg.norm(R) < args.newton_tol:
                    break
                Qf = Qf - np.linalg.solve(J, R)
            for key, val in (("hb_point", i), ("omega_rad_s", om),
                             ("a1_amplitude_m", float(a1_hb[i])),
                             ("a1_amplitude_m_fine", float(np.hypot(Qf[1], Qf[2]))),
                             ("mean_m", float(Q_hb[i][0])), ("mean_m_fine", float(Qf[0])),
                             ("residual_norm_fine", float(np.linalg.norm(R)))):
                cols[key].append(val)
        write_csv(args.out_dir / f"nlvib_aft_check_H{H:02d}.csv", cols)

    if args.shooting_steps > 0:
        # NLvib's example 03 judges stability by shooting and Floquet multipliers (its
        # harmonic balance has none). NLvib-py's shooting residual (Newmark, n_steps per
        # period; J = Phi - I) is solved by Newton at fixed frequency, started from the
        # harmonic-balance orbit of the largest H at a selection of its points.
        n_steps = args.shooting_steps
        H, Q_hb, omega_hb, a1_hb, x_max_hb = last_hb
        fold_i = [r["point"] for r in fold_rows
                  if r["source"] == "nlvib_hb" and r["harmonics_H"] == H]
        picked = [i for i in range(0, len(omega_hb), args.shooting_every)
                  if x_max_hb[i] > args.gap - 0.1]
        for i in fold_i:
            picked += list(range(max(0, i - 3), min(len(omega_hb), i + 4)))
        picked = sorted(set(picked))
        M, D, K = (mat.toarray() for mat in (system.M, system.D, system.K))

        def fnl(q, dq):
            return system.eval_nonlinear_forces(q, dq)[0]

        def f_ext(omega):
            return lambda t: np.array([args.force * math.cos(omega * t)])

        cols = {k: [] for k in (
            "hb_point", "omega_rad_s", "hb_a1_amplitude_m", "q0_m", "dq0_m_s",
            "newton_iterations", "residual_norm", "converged", "a1_amplitude_m", "mean_m", "x_max_m",
            "mu1_re", "mu1_im", "mu2_re", "mu2_im", "max_floquet_modulus", "stable")}
        t0 = time.perf_counter()
        hh = np.arange(1, H + 1)
        for i in picked:
            om = float(omega_hb[i])
            Qi = Q_hb[i]
            y = np.array([Qi[0] + Qi[1::2].sum(), float(om * (hh * Qi[2::2]).sum())])
            # Newton with backtracking on |R| (the Newmark map is only piecewise smooth: the
            # contact switches at time steps, and full steps can cycle across a switch).
            R, J = shooting_residual(y, om, system, 1, n_steps, f_ext(om))
            it = 0
            while np.linalg.norm(R) >= args.newton_tol and it < 40:
                it += 1
                step = np.linalg.solve(J, R)
                lam = 1.0
                while True:
                    y_try = y - lam * step
                    R_try, J_try = shooting_residual(y_try, om, system, 1, n_steps, f_ext(om))
                    if np.linalg.norm(R_try) < np.linalg.norm(R) or lam < 1e-3:
                        break
                    lam /= 2
                y, R, J = y_try, R_try, J_try
            mu = np.linalg.eigvals(J + np.eye(2))
            mu = mu[np.argsort(-np.abs(mu))]
            # The orbit on NLvib-py's Newmark grid, for its first harmonic (as NLvib's
            # example 03: 2 |fft(q)[1]| / N), mean and maximum.
            dt = 2.0 * math.pi / om / n_steps
            q, dq = y[:1], y[1:]
            ddq = np.linalg.solve(M, f_ext(om)(0.0) - D @ dq - K @ q - fnl(q, dq))
            state = y.copy()
            qs = np.empty(n_steps)
            for j in range(n_steps):
                qs[j] = state[0]
                state, ddq = newmark_step(state, f_ext(om)((j + 1) * dt), M, D, K, fnl, dt,
                                          ddq_n=ddq)
            spec = np.fft.rfft(qs) / n_steps
            for key, val in (
                ("hb_point", i), ("omega_rad_s", om), ("hb_a1_amplitude_m", float(a1_hb[i])),
                ("q0_m", float(y[0])), ("dq0_m_s", float(y[1])), ("newton_iterations", it),
                ("residual_norm", float(np.linalg.norm(R))),
                ("converged", bool(np.linalg.norm(R) < args.newton_tol)),
                ("a1_amplitude_m", float(2.0 * abs(spec[1]))), ("mean_m", float(spec[0].real)),
                ("x_max_m", float(qs.max())), ("mu1_re", float(mu[0].real)),
                ("mu1_im", float(mu[0].imag)), ("mu2_re", float(mu[1].real)),
                ("mu2_im", float(mu[1].imag)), ("max_floquet_modulus", float(abs(mu[0]))),
                ("stable", bool(abs(mu[0]) <= 1.0)),
            ):
                cols[key].append(val)
        wall = time.perf_counter() - t0
        print(f"shooting: {len(picked)} points, {wall:.1f} s", file=sys.stderr)
        write_csv(args.out_dir / f"nlvib_shooting_N{n_steps}.csv", cols)
        runs.append(("shooting", n_steps, len(picked), wall, ""))

    if fold_rows:
        write_csv(args.out_dir / "nlvib_folds.csv",
                  {k: [r[k] for r in fold_rows] for k in fold_rows[0]})

    with open(args.out_dir / "nlvib_run.toml", "w") as fh:
        fh.write("# Written by run_sdof_unilateral.py; see PROVENANCE.md.\n")
        fh.write(f'command = "{" ".join([Path(sys.argv[0]).name] + sys.argv[1:])}"\n')
        fh.write(f'python = "{platform.python_version()}"\n')
        fh.write(f'numpy = "{np.__version__}"\nscipy = "{scipy.__version__}"\n')
        fh.write(f'nlvib_py_version = "{getattr(nlvib, "__version__", "unknown")}"\n')
        fh.write(f'nlvib_py_src_sha256 = "{source_digest(src)}"\n')
        fh.write(f"n_time = {args.n_time}\nnewton_tol = {args.newton_tol}\n")
        fh.write(f"ds_initial = {args.ds_initial}\nds_max = {args.ds_max}\nds_min = {args.ds_min}\n")
        for kind, size, n, _wall, message in runs:
            key = "harmonics_H" if kind == "hb" else "newmark_steps_per_period"
            fh.write(f'\n[[run]]\nmethod = "{kind}"\n{key} = {size}\npoints = {n}\n')
            if message:
                fh.write(f'end = "{message}"\n')
    for r in fold_rows:
        print(f"{r['source']} H={r['harmonics_H']} {r['kind']}: omega={r['omega_rad_s']:.6f} "
              f"a1={r['a1_amplitude_m']:.6f}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
