"""An independent simulation of the band-limit study's rigid-stop device: the drive's mean
power under band-limited white noise, against the white-noise law m Sa / 2.

The equations are those of `data/validation/random_restitution.toml` (its values written
below): a linear piezoelectric harvester, m x'' = -k x - c x' + theta V + m a(t),
Cp V' + V / R + theta x' = 0, between two rigid stops at +-gap with restitution e. The method
is not the Rust model's: the noise is generated here (numpy's PCG64, a brick-wall FFT filter
to |f| < B over the whole record, two-sided level Sa = 1e-3 g^2/Hz, sampled at 10 B), read
linearly between samples as the model reads it; between samples the linear system is
propagated exactly (eigen-decomposition with the ramp's particular solution); a step that may
reach a stop is sub-sampled 16 times and the crossing located by bisection on the exact
solution, where x' -> -e x'; a mass that chatters more than 30 times within one step rests
on the stop for the rest of it. The drive's work, int m a x' dt, is taken by 4-point
Gauss-Legendre on the exact solution between events. Each record runs 0.05 s from rest
before its analysed window.

Usage: python3 independent_rigid.py RECORDS BANDWIDTH_HZ RECORD_S E GAP_M SEED
prints the shortfall 1 - P / (m Sa / 2) with its 95 % interval (1.96 standard errors over
the records) and the impact rate, and a JSON line with the same numbers.
"""
import sys
import numpy as np

G = 9.81
# data/validation/random_restitution.toml: mechanics, transducer and load.
m, k, c = 0.01, 15791.0, 2.513
theta, cp, R = 5e-3, 50e-9, 16e3


def model():
    # state (x, v, V); Cp V' + V/R + theta v = 0 ; m v' = -k x - c v + theta V + m a
    A = np.array([[0, 1, 0],
                  [-k / m, -c / m, theta / m],
                  [0, -theta / cp, -1 / (R * cp)]], dtype=float)
    b = np.array([0.0, 1.0, 0.0])
    return A, b


A, bvec = model()
lam, V = np.linalg.eig(A)
Vi = np.linalg.inv(V)
Ainv = np.linalg.inv(A)


def expA(tau):
    """e^{A tau} for an array of tau: (n, 3, 3) real."""
    tau = np.atleast_1d(tau)
    e = np.exp(np.outer(tau, lam))  # (n,3)
    return np.real((V[None, :, :] * e[:, None, :]) @ Vi)


def propagate(y0, a0, a1, tau):
    """Exact y(tau) from y0 with input a0 + a1 t (vectorized over rows; tau scalar or per row)."""
    q = -(Ainv @ bvec)[None, :] * a1[:, None]
    p = (Ainv @ (q.T - np.outer(bvec, a0))).T
    E = expA(tau)
    if E.shape[0] == 1:
        E = np.broadcast_to(E, (y0.shape[0], 3, 3))
    tau = np.broadcast_to(np.atleast_1d(tau), (y0.shape[0],))
    return np.einsum('nij,nj->ni', E, y0 - p) + p + q * tau[:, None]


GLX = np.array([-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526])
GLW = np.array([0.3478548451374538, 0.6521451548725462, 0.6521451548725462, 0.3478548451374538])


def drive_work(y0, a0, a1, h):
    """int_0^h a(t) v(t) dt per row (4-point Gauss-Legendre on the exact solution)."""
    tot = np.zeros(y0.shape[0])
    for xg, wg in zip(GLX, GLW):
        t = 0.5 * h * (1 + xg)
        y = propagate(y0, a0, a1, t)
        tot += 0.5 * h * wg * (a0 + a1 * t) * y[:, 1]
    return tot


def noise(rng, n, fs, B, S):
    """Band-limited Gaussian noise, two-sided level S flat on |f| < B, n samples at fs."""
    w = rng.standard_normal(n)
    F = np.fft.rfft(w)
    f = np.fft.rfftfreq(n, 1 / fs)
    F[f >= B] = 0
    x = np.fft.irfft(F, n)
    # white samples of variance 1 have two-sided density 1/fs; keep |f| < B: variance 2B/fs.
    return x * np.sqrt(S * fs)


def run(N, B, T, e, gap, seed, pre=0.05):
    fs = 10 * B
    h = 1 / fs
    S = 1e-3 * G * G
    rng = np.random.default_rng(seed)
    n = int(round((T + pre) * fs)) + 2
    n_pre = int(round(pre * fs))
    a = np.stack([noise(rng, n, fs, B, S) for _ in range(N)])  # (N, n)
    y = np.zeros((N, 3))
    work = np.zeros(N)
    impacts = np.zeros(N)
    sub = 16
    stuck_steps = [0]
    Esub = expA(np.arange(1, sub + 1) * h / sub)  # (sub,3,3)
    for i in range(n - 1):
        a0 = a[:, i]
        a1 = (a[:, i + 1] - a[:, i]) / h
        y1 = propagate(y, a0, a1, h)
        # rows that may touch a stop within the step: check at sub points
        near = (np.abs(y[:, 0]) + np.abs(y[:, 1]) * h + 500.0 * h * h > gap) | (np.abs(y1[:, 0]) > gap)
        w = drive_work(y, a0, a1, h)
        if near.any():
            idx = np.nonzero(near)[0]
            yj = y[idx].copy()
            a0j, a1j = a0[idx], a1[idx]
            t0 = np.zeros(len(idx))
            wj = np.zeros(len(idx))
            nimp = np.zeros(len(idx))
            active = np.ones(len(idx), bool)
            frac = np.arange(1, sub + 1) / sub
            while active.any():
                ii = np.nonzero(active)[0]
                na = len(ii)
                rem = h - t0[ii]
                taus = (rem[:, None] * frac[None, :]).ravel()
                ain = a0j[ii] + a1j[ii] * t0[ii]
                ys = propagate(np.repeat(yj[ii], sub, 0), np.repeat(ain, sub),
                               np.repeat(a1j[ii], sub), taus).reshape(na, sub, 3)
                over = np.abs(ys[:, :, 0]) > gap
                has = over.any(1)
                fin = ii[~has]
                if len(fin):
                    wj[fin] += drive_work(yj[fin], a0j[fin] + a1j[fin] * t0[fin], a1j[fin], h - t0[fin])
                    yj[fin] = ys[~has, -1]
                    active[fin] = False
                hit = ii[has]
                if len(hit) == 0:
                    continue
                q = over[has].argmax(1)
                remh = rem[has]
                lo = np.where(q == 0, 0.0, remh * q / sub)
                hi = remh * (q + 1) / sub
                side = np.sign(ys[has, q, 0])
                ah = a0j[hit] + a1j[hit] * t0[hit]
                for _ in range(32):
                    mid = 0.5 * (lo + hi)
                    ym = propagate(yj[hit], ah, a1j[hit], mid)
                    beyond = side * ym[:, 0] > gap
                    hi = np.where(beyond, mid, hi)
                    lo = np.where(beyond, lo, mid)
                yc = propagate(yj[hit], ah, a1j[hit], lo)
                wj[hit] += drive_work(yj[hit], ah, a1j[hit], lo)
                yc[:, 0] = side * gap
                yc[:, 1] = -e * yc[:, 1]
                yj[hit] = yc
                t0[hit] += lo
                nimp[hit] += 1
                # Chatter that does not end within the step: the mass rests on the stop
                # for the rest of it (v = 0, no drive work).
                stuck = hit[nimp[hit] > 30]
                if len(stuck):
                    yj[stuck, 1] = 0.0
                    active[stuck] = False
                    stuck_steps[0] += len(stuck)
            w[idx] = wj
            y1[idx] = yj
            if i >= n_pre:
                impacts[idx] += nimp
        if i >= n_pre:
            work += w
        y = y1
    Tan = (n - 1 - n_pre) * h
    P = m * work / Tan
    law = m * S / 2
    short = 1 - P / law
    print('stuck steps', stuck_steps[0])
    return short, impacts / Tan


if __name__ == "__main__":
    N, B, T, e, gap, seed = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5]), int(sys.argv[6])
    s, nu = run(N, B, T, e, gap, seed)
    mu, sd = s.mean(), s.std(ddof=1)
    print(f"B={B} e={e} gap={gap} N={N}: shortfall {100*mu:.4f} +- {100*1.96*sd/np.sqrt(N):.4f} %, impacts/s {nu.mean():.2f}")
    damper = (c / m) / (np.pi ** 2 * B)
    coef = (mu - damper) / (nu.mean() / (np.pi ** 2 * B))
    print(f"damper {100*damper:.4f} %, impact coefficient {coef:.3f} +- {1.96*sd/np.sqrt(N)/(nu.mean()/(np.pi**2*B)):.3f} (1+e = {1+e})")
    import json
    print(json.dumps(dict(records=N, bandwidth_hz=B, record_s=T, restitution=e, gap_m=gap,
                          seed=seed, shortfall=float(mu),
                          shortfall_ci95=float(1.96 * sd / np.sqrt(N)),
                          impacts_per_s=float(nu.mean()),
                          impacts_per_s_ci95=float(1.96 * nu.std(ddof=1) / np.sqrt(N)))))
