"""NLvib's two-DOF oscillator with a unilateral spring, by NLvib-py: HB branch, Floquet, events.

Our driver (no NLvib code): it imports NLvib-py from an outside checkout (--nlvib-src;
https://github.com/julianjurai/NLvib-py, commit in PROVENANCE.md) and uses its system
(ChainOfOscillators, unilateral_spring), its harmonic-balance residual (hb_residual) and its
Newmark shooting with monodromy (shooting_residual). The problem is NLvib's example
EXAMPLES/03_twoDOFoscillator_unilateralSpring (NLvib-py's examples/03_two_dof_unilateral):
masses [1, 1], ki = [0, 1, 1], di = 0.03 ki, a unilateral spring 100 max(q0 - 1, 0), the force
0.1 cos(Om t) on DOF 1, Om from 0.5 to 0.8.

Steps (each writes a file of --out-dir; --stage runs a part, the branch's states cached in
branch_H<H>.npy):
1. hb_H<H>.csv: the HB branch (H harmonics) from Om = 0.5 to 0.8 by a Keller pseudo-arclength
   on [Q; Om] whose steps are rejected when Om moves by more than --max-dom (NLvib-py's
   ContinuationSolver, as its example calls it, jumps from Om = 0.58 to 39 where contact
   begins).
2. shooting_N<n>.csv: NLvib-py's Newmark shooting (n steps a period, the first --ntd) solved by
   Newton at every --scan-every-th HB point's Om from the HB orbit's state at t = 0; the Floquet
   multipliers are the eigenvalues of its monodromy (what the MATLAB example does with its own
   shooting).
3. events.csv: where the largest multiplier modulus crosses 1 between two scanned points,
   located by bisection along the branch (Om and the starting state linear between its
   points) to --bisect-tol in Om, for each --ntd; the kind from the critical multiplier (real
   < 0: period doubling; complex: Neimark-Sacker; real > 0: fold).
4. points.csv: at Om = 0.50, 0.52, ..., 0.80, every solution of the branch (Newton at fixed Om
   from the bracketing HB points), at H and at --h-check, with the first-harmonic amplitudes
   of both DOFs and the H solution's state at t = 0.
5. peak.csv: the largest first-harmonic amplitude of DOF 1 and its Om, for H and --h-check
   (the latter continued over a window around H's peak): the vertex of the parabola in the
   arclength through the largest point and its two neighbours.
"""
import argparse
import hashlib
import platform
import sys
import time
from pathlib import Path

import numpy as np

N_DOF = 2
F = 0.1


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--nlvib-src", type=Path, required=True)
    p.add_argument("--out-dir", type=Path, default=Path("."))
    p.add_argument("--harmonics", type=int, default=21, help="the example's H")
    p.add_argument("--h-check", type=int, default=41, help="H of the truncation estimate")
    p.add_argument("--ntd", default="4096,8192", help="Newmark steps per period, comma-separated")
    p.add_argument("--max-dom", type=float, default=0.002)
    p.add_argument("--ds-max", type=float, default=0.01)
    p.add_argument("--bisect-tol", type=float, default=1e-6)
    p.add_argument("--scan-every", type=int, default=2,
                   help="shoot from every n-th branch point to find the crossings")
    p.add_argument("--range", default=None,
                   help="A:B: the floquet stage scans branch points A to B only and bisects "
                        "only crossings inside them (files suffixed _A_B; the runs' files are "
                        "concatenated afterwards)")
    p.add_argument("--stage", choices=["all", "branch", "points", "floquet"], default="all",
                   help="branch: step 1 (and its states, branch_H<H>.npy); points: steps 4-5; "
                        "floquet: steps 2-3 (the last two read branch_H<H>.npy)")
    return p.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    sys.path.insert(0, str(args.nlvib_src))
    import scipy
    import nlvib
    from nlvib.nonlinearities.elements import unilateral_spring
    from nlvib.systems.oscillators import ChainOfOscillators
    from nlvib.solvers.harmonic_balance import hb_residual, _linear_residual
    from nlvib.solvers.shooting import shooting_residual

    system = ChainOfOscillators(masses=[1.0, 1.0], stiffnesses=[0.0, 1.0, 1.0],
                                dampings=[0.0, 0.03, 0.03])
    system.add_nonlinear_element(unilateral_spring(k=100.0, gap=1.0, dof_index=0))
    exc = {"dof": 1, "amplitude": F}
    out = args.out_dir
    t_start = time.time()

    def log(msg):
        print(f"[{time.time() - t_start:7.0f} s] {msg}", file=sys.stderr, flush=True)

    def res(Q, om, H):
        return hb_residual(Q, om, system, H, exc)

    def dres_dom(Q, om, H):
        # The contact force depends on q alone, so R depends on Om through Z(Om) Q only.
        h = 1e-6
        lin = lambda w: _linear_residual(Q, w, system.M, system.D, system.K, N_DOF, H)  # noqa
        return (lin(om + h) - lin(om - h)) / (2 * h)

    def newton_fixed(Q, om, H, tol=1e-10, iters=30):
        for _ in range(iters):
            R, J = res(Q, om, H)
            if np.linalg.norm(R) < tol:
                return Q, True
            Q = Q + np.linalg.solve(J, -R)
        return Q, np.linalg.norm(res(Q, om, H)[0]) < tol

    def tangent(Q, om, H, prev):
        _, J = res(Q, om, H)
        A = np.vstack([np.column_stack([J, dres_dom(Q, om, H)]), prev])
        t = np.linalg.solve(A, np.concatenate([np.zeros(len(Q)), [1.0]]))
        t /= np.linalg.norm(t)
        return t if t @ prev >= 0 else -t

    def arclength(Q, om, H, stop, ds=0.002, ds_min=1e-8):
        """Keller pseudo-arclength from (Q, om) with Om increasing, until stop(z) is true."""
        z = np.append(Q, om)
        t = tangent(Q, om, H, np.append(np.zeros(len(Q)), 1.0))
        pts = [z.copy()]
        while not stop(z, len(pts)):
            zc = z + ds * t
            ok = False
            for it in range(12):
                R, J = res(zc[:-1], zc[-1], H)
                g = t @ (zc - z) - ds
                if np.linalg.norm(R) < 1e-10 and abs(g) < 1e-12:
                    ok = True
                    break
                A = np.vstack([np.column_stack([J, dres_dom(zc[:-1], zc[-1], H)]), t])
                zc = zc - np.linalg.solve(A, np.concatenate([R, [g]]))
            if not ok or abs(zc[-1] - z[-1]) > args.max_dom:
                ds *= 0.5
                if ds < ds_min:
                    raise RuntimeError(f"H={H}: step below {ds_min} at Om = {z[-1]}")
                continue
            t = tangent(zc[:-1], zc[-1], H, t)
            z = zc
            pts.append(z.copy())
            if len(pts) % 50 == 0:
                log(f"H={H}: {len(pts)} points, Om = {z[-1]:.5f}")
            if it < 4:
                ds = min(2 * ds, args.ds_max)
        return np.array(pts)

    def amp(Q, d):
        return float(np.hypot(Q[N_DOF + d], Q[2 * N_DOF + d]))

    def state0(Q, om, H):
        """[q0, q1, v0, v1] of the series at t = 0."""
        q = Q[0:N_DOF].copy()
        v = np.zeros(N_DOF)
        for h in range(1, H + 1):
            q += Q[(2 * h - 1) * N_DOF:2 * h * N_DOF]
            v += h * om * Q[2 * h * N_DOF:(2 * h + 1) * N_DOF]
        return np.concatenate([q, v])

    def x0_max(Q, H):
        th = np.linspace(0, 2 * np.pi, 1 << 14, endpoint=False)
        q = Q[0] + sum(Q[(2 * h - 1) * N_DOF] * np.cos(h * th) + Q[2 * h * N_DOF] * np.sin(h * th)
                       for h in range(1, H + 1))
        return float(q.max())

    def pad(Q, H_from, H_to):
        P = np.zeros(N_DOF * (2 * H_to + 1))
        P[:len(Q)] = Q
        return P

    def shoot(y, om, ntd):
        fext = lambda t: np.array([0.0, F * np.cos(om * t)])  # noqa: E731
        it = 0
        for it in range(15):
            R, J = shooting_residual(y, om, system, n_periods=1, n_steps=ntd, f_ext_fn=fext)
            if np.linalg.norm(R) < 1e-10:
                break
            y = y + np.linalg.solve(J, -R)
        R, J = shooting_residual(y, om, system, n_periods=1, n_steps=ntd, f_ext_fn=fext)
        mu = np.linalg.eigvals(J + np.eye(2 * N_DOF))
        mu = np.array(sorted(mu, key=lambda m: -abs(m)))
        return y, mu, float(np.linalg.norm(R)), it

    def arc(pts):
        return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])

    def write_csv(name, header, rows):
        with open(out / name, "w") as fh:
            fh.write(",".join(header) + "\n")
            for r in rows:
                fh.write(",".join(f"{v:.12g}" if isinstance(v, float) else str(v) for v in r)
                         + "\n")

    H, H2 = args.harmonics, args.h_check
    ntds = [int(n) for n in args.ntd.split(",")]

    # 1. The branch.
    cache = out / f"branch_H{H}.npy"
    if args.stage in ("points", "floquet"):
        branch = np.load(cache)
    else:
        Q0, ok = newton_fixed(np.zeros(N_DOF * (2 * H + 1)), 0.5, H)
        branch = arclength(Q0, 0.5, H, lambda z, n: z[-1] > 0.8)
        np.save(cache, branch)
    s = arc(branch)
    log(f"H={H}: branch of {len(branch)} points")
    if args.stage in ("all", "branch"):
        write_csv(f"hb_H{H}.csv",
              ["point", "arclength", "omega_rad_s", "a0_amplitude_m", "a1_amplitude_m",
               "mean0_m", "x0_max_m"],
              [(k, s[k], z[-1], amp(z[:-1], 0), amp(z[:-1], 1), z[0], x0_max(z[:-1], H))
               for k, z in enumerate(branch)])
    if args.stage == "branch":
        return 0

    if args.stage in ("all", "points"):
        # 4. Fixed-frequency points, at H and H2, every solution of the branch.
        pt_rows = []
        for om in np.round(np.arange(0.50, 0.8001, 0.02), 10):
            for k in range(len(branch) - 1):
                a, b = branch[k][-1], branch[k + 1][-1]
                if not ((a - om) * (b - om) <= 0 and (b != om or k + 2 == len(branch))):
                    continue
                tau = 0.0 if a == b else (om - a) / (b - a)
                Q, ok1 = newton_fixed((1 - tau) * branch[k][:-1] + tau * branch[k + 1][:-1], om, H)
                Q2, ok2 = newton_fixed(pad(Q, H, H2), om, H2)
                y = state0(Q, om, H)
                _, mu, _, _ = shoot(y, om, ntds[0])
                pt_rows.append((float(om), k, amp(Q, 0), amp(Q, 1), amp(Q2, 0), amp(Q2, 1),
                                x0_max(Q, H), *[float(v) for v in y], float(abs(mu[0])),
                                str(ok1 and ok2).lower()))
                log(f"point Om = {om:.2f} (segment {k}): a1 {amp(Q, 1):.6f} / {amp(Q2, 1):.6f}")
        write_csv("points.csv",
                  ["omega_rad_s", "after_hb_point", f"a0_amplitude_m_h{H}", f"a1_amplitude_m_h{H}",
                   f"a0_amplitude_m_h{H2}", f"a1_amplitude_m_h{H2}", f"x0_max_m_h{H}",
                   "q0_m", "q1_m", "v0_m_s", "v1_m_s", f"max_modulus_n{ntds[0]}", "converged"],
                  pt_rows)

        # 5. The peak of a1, at H and (over a window) at H2.
        def peak(pts):
            a1 = np.array([amp(z[:-1], 1) for z in pts])
            k = int(np.argmax(a1))
            if k == 0 or k == len(pts) - 1:
                raise RuntimeError("the peak is at an end of its branch")
            ss = arc(pts)[k - 1:k + 2]
            ca = np.polyfit(ss, a1[k - 1:k + 2], 2)
            sv = -ca[1] / (2 * ca[0])
            co = np.polyfit(ss, [z[-1] for z in pts[k - 1:k + 2]], 2)
            return float(np.polyval(co, sv)), float(np.polyval(ca, sv)), k

        om_p, a_p, kp = peak(branch)
        k0 = max(kp - 8, 0)
        start2, _ = newton_fixed(pad(branch[k0][:-1], H, H2), branch[k0][-1], H2)
        window = arclength(start2, branch[k0][-1], H2,
                           lambda z, n: n > 16 and amp(z[:-1], 1) < a_p - 0.05)
        om_p2, a_p2, _ = peak(window)
        log(f"peak H={H}: Om {om_p:.7f} a1 {a_p:.7f}; H={H2}: Om {om_p2:.7f} a1 {a_p2:.7f}")
        write_csv("peak.csv", ["harmonics_H", "omega_rad_s", "a1_amplitude_m"],
                  [(H, om_p, a_p), (H2, om_p2, a_p2)])


    if args.stage in ("all", "floquet"):
        # 2. Floquet multipliers at every --scan-every-th point of the branch (and its last).
        def at(tau):
            """The branch, linear between its points, at the real index tau."""
            j = min(int(np.floor(tau)), len(branch) - 2)
            f = tau - j
            return (1 - f) * branch[j] + f * branch[j + 1]

        first, last = 0, len(branch) - 1
        suffix = ""
        if args.range:
            first, last = (int(v) for v in args.range.split(":"))
            suffix = f"_{first}_{last}"
        scanned = list(range(first, last + 1, args.scan_every))
        if scanned[-1] != last:
            scanned.append(last)
        ntd = ntds[0]
        rows, mods = [], []
        for k in scanned:
            z = branch[k]
            y, mu, r, it = shoot(state0(z[:-1], z[-1], H), z[-1], ntd)
            mods.append(mu)
            rows.append((k, z[-1], it, r, *[v for m in mu for v in (m.real, m.imag)],
                         float(abs(mu[0]))))
        write_csv(f"shooting_N{ntd}{suffix}.csv",
                  ["hb_point", "omega_rad_s", "newton_iterations", "residual_norm",
                   "mu1_re", "mu1_im", "mu2_re", "mu2_im", "mu3_re", "mu3_im", "mu4_re",
                   "mu4_im", "max_modulus"], rows)
        log(f"shooting N={ntd}: {len(scanned)} points")

        # 3. Events: crossings of |mu|max = 1 between scanned points, bisected on the branch
        #    for every --ntd (the finer ones from the same bracket, widened by a scan step).
        def kind_of(mu):
            m = mu[0]
            if abs(m.imag) > 1e-6 * abs(m):
                return "neimark-sacker"
            return "period doubling" if m.real < 0 else "fold"

        def gval(tau, n):
            z = at(tau)
            _, mu, _, _ = shoot(state0(z[:-1], z[-1], H), z[-1], n)
            return abs(mu[0]) - 1.0, mu

        ev_rows = []
        g = [abs(mu[0]) - 1.0 for mu in mods]
        for i in range(len(scanned) - 1):
            if (g[i] > 0) == (g[i + 1] > 0):
                continue
            for n in ntds:
                lo, hi = float(scanned[i]), float(scanned[i + 1])
                glo, ghi = g[i], g[i + 1]
                mlo, mhi = mods[i], mods[i + 1]
                if n != ntd:
                    lo, hi = max(lo - args.scan_every, 0.0), min(hi + args.scan_every,
                                                                 len(branch) - 1.0)
                    (glo, mlo), (ghi, mhi) = gval(lo, n), gval(hi, n)
                    if (glo > 0) == (ghi > 0):
                        log(f"N={n}: no crossing between points {lo} and {hi}")
                        continue
                while abs(at(hi)[-1] - at(lo)[-1]) > args.bisect_tol and hi - lo > 1e-9:
                    mid = 0.5 * (lo + hi)
                    gm, mm = gval(mid, n)
                    if (gm > 0) == (glo > 0):
                        lo, glo, mlo = mid, gm, mm
                    else:
                        hi, ghi, mhi = mid, gm, mm
                z = at(0.5 * (lo + hi))
                crit = mhi if glo < 0 else mlo
                ev_rows.append((n, kind_of(crit), f"{0.5 * (lo + hi):.6f}", float(z[-1]),
                                amp(z[:-1], 1), "unstable" if glo < 0 else "stable",
                                float(crit[0].real), float(crit[0].imag)))
                log(f"N={n}: {kind_of(crit)} at Om = {z[-1]:.7f} (branch index "
                    f"{0.5 * (lo + hi):.3f})")
        write_csv(f"events{suffix}.csv", ["newmark_steps", "kind", "hb_point", "omega_rad_s",
                                 "a1_amplitude_m", "becomes", "mu_re", "mu_im"], ev_rows)

    h = hashlib.sha256()
    for f in sorted((args.nlvib_src / "nlvib").rglob("*.py")):
        h.update(str(f.relative_to(args.nlvib_src)).encode())
        h.update(f.read_bytes())
    with open(out / f"nlvib_run_{args.stage}.toml", "w") as fh:
        fh.write("# Written by run_2dof_unilateral.py; see PROVENANCE.md.\n")
        fh.write(f'command = "{" ".join([Path(sys.argv[0]).name] + sys.argv[1:])}"\n')
        fh.write(f'python = "{platform.python_version()}"\n')
        fh.write(f'numpy = "{np.__version__}"\nscipy = "{scipy.__version__}"\n')
        fh.write(f'nlvib_py_version = "{getattr(nlvib, "__version__", "unknown")}"\n')
        fh.write(f'nlvib_py_src_sha256 = "{h.hexdigest()}"\n')
        fh.write(f"harmonics = {H}\nh_check = {H2}\nnewmark_steps = {ntds}\n")
        fh.write(f"max_dom = {args.max_dom}\nds_max = {args.ds_max}\n")
        fh.write(f"bisect_tol = {args.bisect_tol}\nbranch_points = {len(branch)}\n")
        fh.write(f"wall_s = {time.time() - t_start:.0f}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
