#!/usr/bin/env python3
"""Exact period-one orbits of a one-sided (unilateral) spring oscillator by shooting.

An independent reference (numpy and scipy only; neither NLvib nor the endstop library) for

    m x'' + d x' + k x + kc * max(x - gap, 0) = F cos(omega t),

the single-degree-of-freedom problem also computed with NLvib-py's harmonic balance
(``run_sdof_unilateral.py`` beside this file). Time-domain shooting has no harmonic truncation,
so the gap between these orbits and the harmonic-balance ones is NLvib's truncation error.

Method
------
* Time is scaled to the forcing phase tau = omega t, so one period is tau in [0, 2 pi].
* ``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-10, atol 1e-12) integrates one smooth piece
  of the vector field at a time (free flight, or contact with the spring engaged); a terminal
  event on x - gap = 0 ends the piece and the other piece starts from the event state. The
  flow is therefore never integrated across the kink of max(., 0).
* Newton on the period map P(y0, omega) - y0 = 0 (y0 = (x(0), x'(0))), inside a
  pseudo-arclength continuation in (x0, v0, omega). The Newton Jacobian comes from the
  variational equations integrated with the orbit; the contact force is continuous at the
  gap, so the saltation matrix at a crossing is the identity and the pieces' transition
  matrices simply multiply.
* Floquet multipliers are the eigenvalues of the monodromy matrix by central finite
  differences of the period map (step 1e-5 on each initial state). The multipliers of the
  variational monodromy are stored beside them as a check.
* Turning points (folds): where the omega component of the branch tangent changes sign, the
  fold is solved as the extended system P(y0, omega) - y0 = 0, det(Phi - I) = 0 (a multiplier
  equal to +1) by Newton, starting from the bracketing branch point.

Outputs (in --out-dir): ``shooting_branch.csv`` (every continuation point),
``shooting_folds.csv`` (the refined turning points).

Run: ``python3 shooting_scipy.py --out-dir .`` (numpy and scipy; see PROVENANCE.md for the
versions used and the run time).
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

RTOL = 1e-10
ATOL = 1e-12
FD_STEP = 1e-5
NEWTON_TOL = 1e-10
NEWTON_MAX_ITER = 12
MAX_PIECES_PER_PERIOD = 200
SAMPLES_PER_PERIOD = 4096
FIRST_STEP_ON_GAP = 1e-9
SCAN_STEP = 1e-3  # phase grid on which free flight is checked for missed gap crossings


@dataclass(frozen=True)
class Oscillator:
    """m x'' + d x' + k x + kc max(x - gap, 0) = force cos(omega t)."""

    m: float
    d: float
    k: float
    kc: float
    gap: float
    force: float


@dataclass
class Period:
    """One period of the flow from y0 at forcing frequency omega."""

    y_end: np.ndarray  # state at tau = 2 pi
    phi: np.ndarray  # monodromy from the variational equations (2 x 2)
    dy_domega: np.ndarray  # sensitivity of y_end to omega (2,)
    pieces: list  # (dense solution, contact flag) in order
    x_max: float  # largest displacement over the period (located by an event on x' = 0)
    impacts: int  # number of entries into contact per period


def _rhs(osc: Oscillator, omega: float, contact: bool):
    """Right-hand side in tau of (x, v, Phi (2x2, row major), dy/domega (2))."""
    k_eff = osc.k + (osc.kc if contact else 0.0)
    offset = osc.kc * osc.gap if contact else 0.0
    a = np.array([[0.0, 1.0], [-k_eff / osc.m, -osc.d / osc.m]]) / omega

    def f(tau, z):
        x, v = z[0], z[1]
        acc = (osc.force * math.cos(tau) - osc.d * v - k_eff * x + offset) / osc.m
        fy = np.array([v, acc]) / omega
        phi = z[2:6].reshape(2, 2)
        s = z[6:8]
        dphi = a @ phi
        ds = a @ s - fy / omega  # d/domega of (g(y, tau) / omega) at fixed y
        return np.concatenate([fy, dphi.ravel(), ds])

    return f


def _gap_event(osc: Oscillator, contact: bool):
    def g(tau, z):
        return z[0] - osc.gap

    g.terminal = True
    # A piece ends where the state leaves its side of the gap.
    g.direction = -1.0 if contact else 1.0
    return g


def _turn_event(tau, z):
    return z[1]


_turn_event.direction = -1.0  # x' goes from + to -: a local maximum of x


def _missed_crossing(dense, t0: float, t1: float, gap: float) -> float | None:
    """First upward crossing of x = gap in (t0, t1) on a grid of SCAN_STEP, refined by brentq."""
    n = max(2, int(math.ceil((t1 - t0) / SCAN_STEP)) + 1)
    grid = np.linspace(t0, t1, n)
    above = dense(grid)[0] - gap > 0.0
    above[0] = False
    idx = np.flatnonzero(above)
    if idx.size == 0:
        return None
    i = int(idx[0])
    lo = grid[i - 1]
    if i == 1:
        lo = t0 + FIRST_STEP_ON_GAP
        if dense(lo)[0] - gap >= 0.0:
            return None  # leaves the gap tangentially; no crossing to resolve
    return brentq(lambda t: dense(t)[0] - gap, lo, grid[i], xtol=1e-14, rtol=1e-15)


def one_period(osc: Oscillator, y0: np.ndarray, omega: float) -> Period:
    """Integrate one forcing period piece by piece."""
    x0, v0 = float(y0[0]), float(y0[1])
    contact = x0 > osc.gap or (x0 == osc.gap and v0 > 0.0)
    z = np.concatenate([[x0, v0], np.eye(2).ravel(), np.zeros(2)])
    tau = 0.0
    tau_end = 2.0 * math.pi
    pieces = []
    x_max = -math.inf
    impacts = 0
    for _ in range(MAX_PIECES_PER_PERIOD):
        sol = solve_ivp(
            _rhs(osc, omega, contact),
            (tau, tau_end),
            z,
            method="DOP853",
            rtol=RTOL,
            atol=ATOL,
            dense_output=True,
            events=[_gap_event(osc, contact), _turn_event],
            # A piece that starts on the gap takes a tiny first step, so that the event
            # function has left zero before the first sign check (a short contact would
            # otherwise be found at its own start).
            first_step=FIRST_STEP_ON_GAP if pieces else None,
        )
        if sol.status < 0:
            raise RuntimeError(f"solve_ivp failed at omega={omega}: {sol.message}")
        t1 = float(sol.t[-1])
        ended_at_gap = sol.status == 1
        z_end = sol.y_events[0][0].copy() if ended_at_gap else sol.y[:, -1].copy()
        if not contact:
            # An excursion above the gap shorter than one integrator step changes no sign at
            # the step points and escapes the event; scan the dense output for it.
            missed = _missed_crossing(sol.sol, tau, t1, osc.gap)
            if missed is not None:
                t1, ended_at_gap = missed, True
                z_end = sol.sol(t1)
        pieces.append((sol.sol, contact, tau, t1))
        keep = sol.t <= t1
        x_max = max(x_max, float(np.max(sol.y[0][keep])))
        turns = sol.t_events[1] <= t1
        if np.any(turns):
            x_max = max(x_max, float(np.max(sol.y_events[1][turns, 0])))
        if ended_at_gap:
            tau = t1
            z = z_end
            z[0] = osc.gap
            contact = not contact
            if contact:
                impacts += 1
            continue
        return Period(
            y_end=sol.y[:2, -1].copy(),
            phi=sol.y[2:6, -1].reshape(2, 2).copy(),
            dy_domega=sol.y[6:8, -1].copy(),
            pieces=pieces,
            x_max=x_max,
            impacts=impacts,
        )
    raise RuntimeError(
        f"more than {MAX_PIECES_PER_PERIOD} gap crossings in one period from y0={list(map(float, y0))}, omega={omega!r}"
    )


def sample_period(period: Period, n: int) -> np.ndarray:
    """x at n uniform phases tau_j = 2 pi j / n, from the pieces' dense output."""
    taus = 2.0 * math.pi * np.arange(n) / n
    x = np.empty(n)
    for sol, _contact, t0, t1 in period.pieces:
        sel = (taus >= t0) & (taus <= t1)
        if np.any(sel):
            x[sel] = sol(taus[sel])[0]
    return x


def harmonics(period: Period) -> tuple[float, float, float, float]:
    """Mean, first-harmonic cosine and sine coefficients and magnitude of x(tau)."""
    x = sample_period(period, SAMPLES_PER_PERIOD)
    spec = np.fft.rfft(x) / SAMPLES_PER_PERIOD
    mean = float(spec[0].real)
    a1c = float(2.0 * spec[1].real)
    a1s = float(-2.0 * spec[1].imag)
    return mean, a1c, a1s, math.hypot(a1c, a1s)


def fd_monodromy(osc: Oscillator, y0: np.ndarray, omega: float) -> np.ndarray:
    """Monodromy matrix by central differences of the period map."""
    phi = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = FD_STEP
        yp = one_period(osc, y0 + e, omega).y_end
        ym = one_period(osc, y0 - e, omega).y_end
        phi[:, j] = (yp - ym) / (2.0 * FD_STEP)
    return phi


def residual(osc, z):
    """Period-map residual and its Jacobian w.r.t. (x0, v0, omega)."""
    per = one_period(osc, z[:2], z[2])
    r = per.y_end - z[:2]
    jac = np.hstack([per.phi - np.eye(2), per.dy_domega[:, None]])
    return r, jac, per


def tangent(jac: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """Unit null vector of the 2 x 3 Jacobian, oriented along the previous tangent."""
    _, _, vt = np.linalg.svd(jac)
    t = vt[-1]
    if previous is None:
        if t[2] < 0.0:
            t = -t
    elif t @ previous < 0.0:
        t = -t
    return t / np.linalg.norm(t)


def correct(osc, z_pred, t):
    """Newton on (period map, arclength plane through z_pred normal to t)."""
    z = z_pred.copy()
    for it in range(1, NEWTON_MAX_ITER + 1):
        r, jac, per = residual(osc, z)
        g = np.append(r, t @ (z - z_pred))
        if np.linalg.norm(g) < NEWTON_TOL:
            return z, jac, per, it
        a = np.vstack([jac, t])
        z = z - np.linalg.solve(a, g)
    return None


def linear_start(osc: Oscillator, omega: float) -> np.ndarray:
    """Initial state of the linear steady state (valid while x stays below the gap)."""
    amp = osc.force / (osc.k - osc.m * omega**2 + 1j * osc.d * omega)
    return np.array([amp.real, -omega * amp.imag])


def fold_system(osc, z):
    r, jac, per = residual(osc, z)
    return np.append(r, np.linalg.det(per.phi - np.eye(2))), per


def refine_fold(osc, z0):
    """Solve P(y0, omega) = y0, det(Phi - I) = 0 by Newton with a difference Jacobian."""
    z = z0.copy()
    for _ in range(30):
        f, per = fold_system(osc, z)
        if np.linalg.norm(f) < 1e-9:
            return z, per
        jac = np.empty((3, 3))
        for j in range(3):
            h = 1e-6 * max(1.0, abs(z[j]))
            e = np.zeros(3)
            e[j] = h
            jac[:, j] = (fold_system(osc, z + e)[0] - fold_system(osc, z - e)[0]) / (2 * h)
        z = z - np.linalg.solve(jac, f)
    raise RuntimeError(f"fold refinement did not converge from {z0}")


def row(osc, z, per, s):
    mean, a1c, a1s, a1 = harmonics(per)
    mu_fd = np.linalg.eigvals(fd_monodromy(osc, z[:2], z[2]))
    mu_var = np.linalg.eigvals(per.phi)
    mu_fd = mu_fd[np.argsort(-np.abs(mu_fd))]
    return {
        "arclength": s,
        "omega_rad_s": z[2],
        "x0_m": z[0],
        "v0_m_s": z[1],
        "a1_amplitude_m": a1,
        "a1_cos_m": a1c,
        "a1_sin_m": a1s,
        "mean_m": mean,
        "x_max_m": per.x_max,
        "impacts_per_period": per.impacts,
        "mu1_re": mu_fd[0].real,
        "mu1_im": mu_fd[0].imag,
        "mu2_re": mu_fd[1].real,
        "mu2_im": mu_fd[1].imag,
        "max_floquet_modulus": float(np.max(np.abs(mu_fd))),
        "max_floquet_modulus_variational": float(np.max(np.abs(mu_var))),
        "stable": bool(np.max(np.abs(mu_fd)) < 1.0),
    }


def grazing_frequencies(osc: Oscillator) -> list[float]:
    """Frequencies where the linear response amplitude equals the gap (closed form).

    F / |k - m w^2 + i d w| = gap  <=>  m^2 u^2 + (d^2 - 2 k m) u + k^2 - (F/gap)^2 = 0, u = w^2.
    """
    roots = np.roots([osc.m**2, osc.d**2 - 2 * osc.k * osc.m, osc.k**2 - (osc.force / osc.gap) ** 2])
    return sorted(math.sqrt(u.real) for u in roots if abs(u.imag) < 1e-14 and u.real > 0)


def continue_branch(osc, omega0, direction, args, stop, segment, log):
    """Pseudo-arclength continuation from the linear orbit at omega0 in the given direction.

    ``stop(row, seen_fold)`` ends the segment (for instance at grazing, where the branch has a
    corner that no smooth predictor follows).
    """
    z = np.append(linear_start(osc, omega0), omega0)
    res = correct(osc, z, np.array([0.0, 0.0, 1.0]))
    if res is None:
        raise RuntimeError(f"no periodic orbit at omega={omega0}")
    z, jac, per, _ = res
    t = tangent(jac, None) * direction
    s = 0.0
    rows = [dict(segment=segment, **row(osc, z, per, s))]
    tangents, points = [t], [z]
    ds = args.ds_max / 4
    seen_fold = False
    while args.omega_start - 1e-9 <= z[2] <= args.omega_end + 1e-9 and len(rows) < 5000:
        cap = args.ds_fold if abs(t[2]) < 0.05 else args.ds_max
        ds = min(ds, cap)
        res = correct(osc, z + ds * t, t)
        if res is None:
            ds /= 2
            if ds < 1e-7:
                raise RuntimeError(f"step size underflow at {z}")
            continue
        z_new, jac, per, it = res
        t_new = tangent(jac, t)
        if t_new @ t < 0.995 and ds > 1e-5:  # turn too sharp: retry shorter
            ds /= 2
            continue
        s += float(np.linalg.norm(z_new - z))
        if t[2] * t_new[2] < 0.0:
            seen_fold = True
        z, t = z_new, t_new
        r = dict(segment=segment, **row(osc, z, per, s))
        rows.append(r)
        tangents.append(t)
        points.append(z)
        if it <= 3:
            ds = min(2 * ds, args.ds_max)
        log(f"seg {segment} s={s:.4f} omega={z[2]:.6f} a1={r['a1_amplitude_m']:.6f} "
            f"pen={r['x_max_m'] - osc.gap:.3e} |mu|max={r['max_floquet_modulus']:.6f}")
        if stop(r, seen_fold):
            break
    return rows, tangents, points


def fmt(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v)).lower()
    if isinstance(v, float):
        return f"{v:.12g}"
    return str(v)


def write_csv(path: Path, data: list[dict]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(data[0].keys()))
        w.writeheader()
        for r in data:
            w.writerow({k: fmt(v) for k, v in r.items()})


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--m", type=float, default=1.0)
    p.add_argument("--d", type=float, default=0.03)
    p.add_argument("--k", type=float, default=1.0)
    p.add_argument("--kc", type=float, default=100.0)
    p.add_argument("--gap", type=float, default=1.0)
    p.add_argument("--force", type=float, default=0.1)
    p.add_argument("--omega-start", type=float, default=0.5)
    p.add_argument("--omega-end", type=float, default=2.5)
    p.add_argument("--ds-max", type=float, default=0.02)
    p.add_argument("--ds-fold", type=float, default=2e-3,
                   help="largest step where the tangent's omega share is below 0.05")
    p.add_argument("--graze-tol", type=float, default=1e-4,
                   help="a segment ends when the orbit's largest penetration x_max - gap "
                        "(after a fold) or its distance to the gap (non-impacting) is below this")
    p.add_argument("--out-dir", type=Path, default=Path("."))
    args = p.parse_args(argv)
    osc = Oscillator(args.m, args.d, args.k, args.kc, args.gap, args.force)

    def log(msg):
        print(msg, file=sys.stderr)

    # Segment 0: from the low end upward, over the fold, down the overhang until the
    # impacting orbit grazes the gap again.
    rows0, tan0, pts0 = continue_branch(
        osc, args.omega_start, 1.0, args,
        lambda r, seen_fold: seen_fold and r["x_max_m"] - osc.gap < args.graze_tol,
        0, log)
    # Segment 1: from the high end downward along the non-impacting orbits until they graze.
    rows1, _, _ = continue_branch(
        osc, args.omega_end, -1.0, args,
        lambda r, seen_fold: osc.gap - r["x_max_m"] < args.graze_tol,
        1, log)

    folds = []
    for i in range(1, len(rows0)):
        if tan0[i - 1][2] * tan0[i][2] < 0.0:
            zf, perf = refine_fold(osc, pts0[i])
            mean, _, _, a1 = harmonics(perf)
            mu = np.linalg.eigvals(fd_monodromy(osc, zf[:2], zf[2]))
            folds.append({
                "kind": "fold_max_omega" if tan0[i - 1][2] > 0 else "fold_min_omega",
                "method": "extended system P(y)=y and det(Phi-I)=0, Newton",
                "omega_rad_s": zf[2],
                "a1_amplitude_m": a1,
                "mean_m": mean,
                "x_max_m": perf.x_max,
                "mu_closest_to_one_re": float(mu[np.argmin(np.abs(mu - 1.0))].real),
            })
    for w in grazing_frequencies(osc):
        folds.append({
            "kind": "grazing",
            "method": "closed form: linear amplitude F/|k - m w^2 + i d w| equals the gap",
            "omega_rad_s": w,
            "a1_amplitude_m": osc.gap,
            "mean_m": 0.0,
            "x_max_m": osc.gap,
            "mu_closest_to_one_re": float("nan"),
        })

    args.out_dir.mkdir(parents=True, exist_ok=True)
    write_csv(args.out_dir / "shooting_branch.csv", rows0 + rows1)
    write_csv(args.out_dir / "shooting_folds.csv", folds)
    for f in folds:
        log(f"{f['kind']}: omega={f['omega_rad_s']:.9f} a1={f['a1_amplitude_m']:.9f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
