#!/usr/bin/env python3
"""NLvib's Duffing example computed with NLvib-py (peer reference).

NLvib's example 01 (``EXAMPLES/01_Duffing/Duffing.m`` of github.com/maltekrack/NLvib):

    mu q'' + zeta q' + kappa q + gamma q^3 = P cos(Om t),
    mu = 1, zeta = 0.05, kappa = 1, gamma = 0.1, P = 0.18, Om from 0.5 to 1.6,

by harmonic balance (alternating frequency-time scheme) and pseudo-arclength continuation in
Om, with NLvib-py (the Python port, github.com/julianjurai/NLvib-py: ``SingleMassOscillator``
plus ``cubic_spring``, ``hb_residual``, ``ContinuationSolver``) for several harmonic
truncations H, and NLvib-py's Newmark shooting with Floquet multipliers at a selection of the
largest H's points (NLvib's harmonic balance has no stability analysis; NLvib-py's
continuation flag is a fold-parity flag and is stored as it is).

NLvib is GPL-3.0 and NLvib-py is its port; neither is part of this repository: this script
imports NLvib-py from an outside checkout (``--nlvib-src``) and contains none of its code. The
CSV helpers and the turning-point rule are those of ``../nlvib/run_sdof_unilateral.py``
(imported from there).

Run (see PROVENANCE.md for the exact command that produced the stored files)::

    python run_duffing.py --nlvib-src /work/peer/NLvib-py/src --out-dir .
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "nlvib"))
from run_sdof_unilateral import source_digest, turning_points, write_csv  # noqa: E402


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nlvib-src", type=Path, default=Path("/work/peer/NLvib-py/src"))
    p.add_argument("--harmonics", default="1,3,5,7,10,15")
    p.add_argument("--mu", type=float, default=1.0)
    p.add_argument("--zeta", type=float, default=0.05)
    p.add_argument("--kappa", type=float, default=1.0)
    p.add_argument("--gamma", type=float, default=0.1)
    p.add_argument("--force", type=float, default=0.18, help="P of P cos(Om t)")
    p.add_argument("--omega-start", type=float, default=0.5)
    p.add_argument("--omega-end", type=float, default=1.6)
    p.add_argument("--n-time", type=int, default=128,
                   help="AFT samples per period (exact for a cubic while n_time > 4 H)")
    p.add_argument("--newton-tol", type=float, default=1e-10)
    p.add_argument("--ds-initial", type=float, default=0.01, help="NLvib's example: ds = .01")
    p.add_argument("--ds-max", type=float, default=0.01)
    p.add_argument("--ds-min", type=float, default=1e-7)
    p.add_argument("--max-steps", type=int, default=5000)
    p.add_argument("--shooting-steps", type=int, default=4096,
                   help="Newmark steps per period for NLvib-py's shooting (0: none)")
    p.add_argument("--shooting-every", type=int, default=5)
    p.add_argument("--out-dir", type=Path, default=Path("."))
    return p.parse_args(argv)


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
    from nlvib.nonlinearities.elements import cubic_spring
    from nlvib.solvers.harmonic_balance import hb_residual
    from nlvib.solvers.shooting import newmark_step, shooting_residual
    from nlvib.systems.oscillators import SingleMassOscillator

    if not Path(nlvib.__file__).resolve().is_relative_to(src):
        print(f"error: nlvib imported from {nlvib.__file__}, not {src}", file=sys.stderr)
        return 2

    system = SingleMassOscillator(m=args.mu, d=args.zeta, k=args.kappa)
    system.add_nonlinear_element(cubic_spring(k3=args.gamma, dof_index=0))
    excitation = {"dof": 0, "amplitude": args.force}
    harmonics = [int(h) for h in args.harmonics.split(",") if h]
    args.out_dir.mkdir(parents=True, exist_ok=True)
    opts = ContinuationOptions(
        ds_initial=args.ds_initial, ds_min=args.ds_min, ds_max=args.ds_max,
        max_steps=args.max_steps, max_newton_iter=25, newton_tol=args.newton_tol,
        adapt_step=True,
        lambda_min=args.omega_start - 0.1 * (args.omega_end - args.omega_start),
        lambda_max=args.omega_end)

    fold_rows, runs, last = [], [], None
    for H in harmonics:
        def residual(Q, omega, H=H):
            return hb_residual(Q, omega, system, H, excitation, n_time=args.n_time)

        Q0 = np.zeros(2 * H + 1)
        for _ in range(50):
            R, J = residual(Q0, args.omega_start)
            if np.linalg.norm(R) < args.newton_tol:
                break
            Q0 = Q0 + np.linalg.solve(J, -R)
        t0 = time.perf_counter()
        result = ContinuationSolver().run(residual, Q0, args.omega_start, opts)
        wall = time.perf_counter() - t0
        print(f"H={H}: {result.n_steps} points, {result.message}, {wall:.1f} s", file=sys.stderr)
        sol = result.solutions
        Q, omega = sol[:, :-1], sol[:, -1]
        arclength = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(sol, axis=0), axis=1))])
        a1 = np.hypot(Q[:, 1], Q[:, 2])
        phase = 2.0 * math.pi * np.arange(4096) / 4096
        hh = np.arange(1, H + 1)
        q_t = Q[:, :1] + Q[:, 1::2] @ np.cos(np.outer(hh, phase)) \
            + Q[:, 2::2] @ np.sin(np.outer(hh, phase))
        x_max = q_t.max(axis=1)
        write_csv(args.out_dir / f"nlvib_hb_H{H:02d}.csv", {
            "point": list(range(len(omega))),
            "arclength": list(map(float, arclength)),
            "omega_rad_s": list(map(float, omega)),
            "a1_amplitude_m": list(map(float, a1)),
            "a1_cos_m": list(map(float, Q[:, 1])),
            "a1_sin_m": list(map(float, Q[:, 2])),
            "mean_m": list(map(float, Q[:, 0])),
            "x_max_m": list(map(float, x_max)),
            "nlvib_unstable_between_folds": [bool(f) for f in np.asarray(result.stability)],
        })
        fold_rows += turning_points(arclength, omega, {"a1_amplitude_m": a1, "x_max_m": x_max},
                                    {"source": "nlvib_hb", "harmonics_H": H})
        runs.append(("hb", H, result.n_steps, result.message))
        last = (H, Q, omega, a1)

    if args.shooting_steps > 0:
        n_steps = args.shooting_steps
        H, Q_hb, omega_hb, a1_hb = last
        fold_i = [r["point"] for r in fold_rows if r["harmonics_H"] == H]
        picked = set(range(0, len(omega_hb), args.shooting_every))
        for i in fold_i:
            picked |= set(range(max(0, i - 3), min(len(omega_hb), i + 4)))
        M, D, K = (mat.toarray() for mat in (system.M, system.D, system.K))

        def fnl(q, dq):
            return system.eval_nonlinear_forces(q, dq)[0]

        def f_ext(om):
            return lambda t: np.array([args.force * math.cos(om * t)])

        cols = {k: [] for k in (
            "hb_point", "omega_rad_s", "hb_a1_amplitude_m", "q0_m", "dq0_m_s",
            "newton_iterations", "residual_norm", "converged", "a1_amplitude_m",
            "mu1_re", "mu1_im", "mu2_re", "mu2_im", "max_floquet_modulus", "stable")}
        hh = np.arange(1, H + 1)
        for i in sorted(picked):
            om = float(omega_hb[i])
            Qi = Q_hb[i]
            y = np.array([Qi[0] + Qi[1::2].sum(), float(om * (hh * Qi[2::2]).sum())])
            R, J = shooting_residual(y, om, system, 1, n_steps, f_ext(om))
            it = 0
            while np.linalg.norm(R) >= 1e-9 and it < 30:
                it += 1
                y = y - np.linalg.solve(J, R)
                R, J = shooting_residual(y, om, system, 1, n_steps, f_ext(om))
            mu = np.linalg.eigvals(J + np.eye(2))
            mu = mu[np.argsort(-np.abs(mu))]
            dt = 2.0 * math.pi / om / n_steps
            q, dq = y[:1], y[1:]
            ddq = np.linalg.solve(M, f_ext(om)(0.0) - D @ dq - K @ q - fnl(q, dq))
            state, qs = y.copy(), np.empty(n_steps)
            for j in range(n_steps):
                qs[j] = state[0]
                state, ddq = newmark_step(state, f_ext(om)((j + 1) * dt), M, D, K, fnl, dt,
                                          ddq_n=ddq)
            spec = np.fft.rfft(qs) / n_steps
            for key, val in (
                ("hb_point", i), ("omega_rad_s", om), ("hb_a1_amplitude_m", float(a1_hb[i])),
                ("q0_m", float(y[0])), ("dq0_m_s", float(y[1])), ("newton_iterations", it),
                ("residual_norm", float(np.linalg.norm(R))),
                ("converged", bool(np.linalg.norm(R) < 1e-9)),
                ("a1_amplitude_m", float(2.0 * abs(spec[1]))),
                ("mu1_re", float(mu[0].real)), ("mu1_im", float(mu[0].imag)),
                ("mu2_re", float(mu[1].real)), ("mu2_im", float(mu[1].imag)),
                ("max_floquet_modulus", float(abs(mu[0]))), ("stable", bool(abs(mu[0]) <= 1.0)),
            ):
                cols[key].append(val)
        write_csv(args.out_dir / f"nlvib_shooting_N{n_steps}.csv", cols)
        runs.append(("shooting", n_steps, len(picked), ""))

    write_csv(args.out_dir / "nlvib_folds.csv", {k: [r[k] for r in fold_rows] for k in fold_rows[0]})
    with open(args.out_dir / "nlvib_run.toml", "w") as fh:
        fh.write("# Written by run_duffing.py; see PROVENANCE.md.\n")
        fh.write(f'command = "{" ".join([Path(sys.argv[0]).name] + sys.argv[1:])}"\n')
        fh.write(f'python = "{platform.python_version()}"\n')
        fh.write(f'numpy = "{np.__version__}"\nscipy = "{scipy.__version__}"\n')
        fh.write(f'nlvib_py_version = "{getattr(nlvib, "__version__", "unknown")}"\n')
        fh.write(f'nlvib_py_src_sha256 = "{source_digest(src)}"\n')
        fh.write(f"n_time = {args.n_time}\nnewton_tol = {args.newton_tol}\n")
        fh.write(f"ds_initial = {args.ds_initial}\nds_max = {args.ds_max}\nds_min = {args.ds_min}\n")
        for kind, size, n, message in runs:
            key = "harmonics_H" if kind == "hb" else "newmark_steps_per_period"
            fh.write(f'\n[[run]]\nmethod = "{kind}"\n{key} = {size}\npoints = {n}\n')
            if message:
                fh.write(f'end = "{message}"\n')
    for r in fold_rows:
        print(f"H={r['harmonics_H']} {r['kind']}: omega={r['omega_rad_s']:.8f} "
              f"a1={r['a1_amplitude_m']:.8f}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
