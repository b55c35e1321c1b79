"""Event-located reference for NLvib's two-DOF unilateral-spring example (our own script: it
imports nothing of NLvib). The system (NLvib's EXAMPLES/03, masses 1 and 1, springs ki = [0 1 1],
dampers 0.03 ki, a one-sided spring 100 beyond 1 on DOF 0, the force 0.1 cos(Om t) on DOF 1):

    q0'' = -(q0 - q1) - 0.03 (q0' - q1') - 100 max(q0 - 1, 0)
    q1'' = -(q1 - q0) - 0.03 (q1' - q0') - q1 - 0.03 q1' + 0.1 cos(Om t)

Writes exact_events.csv:
* grazing: where the linear (contact-free) branch's |Q0| reaches the gap, in closed form
  (|[(K - Om^2 M + i Om D)^-1 F]_0| = 1, brentq to 1e-12);
* neimark-sacker regain: where the largest Floquet multiplier's modulus falls through 1 on the
  contacting branch above grazing;
* period doubling: where a real multiplier reaches -1 on the upper branch below its fold.
Orbits by Newton on the period map; the period map by scipy's DOP853 (rtol 1e-12, atol 1e-14,
max step T/1000) with the contact located as an event (direction-aware); the monodromy by
central differences (h = 1e-6); the frequencies by brentq to 1e-9 rad/s. Starting states are
NLvib-py's shooting states of points.csv at Om = 0.62 and 0.74.

Run: python exact_events.py  (numpy, scipy; see PROVENANCE.md for the versions)."""
import csv
import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

K01, D01, K1, D1, KC, GAP, F = 1.0, 0.03, 1.0, 0.03, 100.0, 1.0, 0.1


def rhs(t, y, om, contact):
    x0, x1, v0, v1 = y
    fc = KC * (x0 - GAP) if contact else 0.0
    a0 = -K01 * (x0 - x1) - D01 * (v0 - v1) - fc
    a1 = -K01 * (x1 - x0) - D01 * (v1 - v0) - K1 * x1 - D1 * v1 + F * np.cos(om * t)
    return [v0, v1, a0, a1]


def flow(y0, om, rtol=1e-12):
    T = 2 * np.pi / om
    t, y = 0.0, np.array(y0, float)
    contact = y[0] > GAP or (y[0] == GAP and y[2] > 0)
    while t < T:
        ev = lambda tt, yy, *a: yy[0] - GAP
        ev.terminal = True
        ev.direction = -1.0 if contact else 1.0
        sol = solve_ivp(rhs, (t, T), y, method="DOP853", rtol=rtol, atol=1e-14,
                        max_step=T / 1000, args=(om, contact), events=ev)
        if sol.status == 1:
            t = sol.t_events[0][0]
            y = sol.y_events[0][0].copy()
            y[0] = GAP
            contact = not contact
        else:
            t, y = T, sol.y[:, -1]
    return y


def monodromy(y0, om, h=1e-6):
    M = np.zeros((4, 4))
    for j in range(4):
        e = np.zeros(4)
        e[j] = h
        M[:, j] = (flow(y0 + e, om) - flow(y0 - e, om)) / (2 * h)
    return M


def periodic(om, y0):
    y = np.array(y0, float)
    for _ in range(30):
        r = flow(y, om) - y
        if np.linalg.norm(r) < 1e-11:
            return y
        y = y - np.linalg.solve(monodromy(y, om) - np.eye(4), r)
    raise RuntimeError(f"Newton did not converge at Om = {om}")


def root(fun, a, b, y0):
    cache = {"y": periodic(a, y0)}

    def g(om):
        cache["y"] = periodic(om, cache["y"])
        return fun(np.linalg.eigvals(monodromy(cache["y"], om)))

    return brentq(g, a, b, xtol=1e-9)


def grazing():
    K = np.array([[K01, -K01], [-K01, K01 + K1]])
    D = np.array([[D01, -D01], [-D01, D01 + D1]])
    f = np.array([0.0, F])
    a0 = lambda w: abs(np.linalg.solve(K - w * w * np.eye(2) + 1j * w * D, f)[0])
    return brentq(lambda w: a0(w) - GAP, 0.58, 0.60, xtol=1e-12)


def most_negative_real(mu):
    real = [m.real for m in mu if abs(m.imag) < 1e-9]
    return -min(real) - 1.0


if __name__ == "__main__":
    y62 = [0.973026199292, 0.646387379401, 0.272264740617, 0.0717195723574]
    y74 = [0.418503193611, 0.417580209927, 0.655914057129, 1.05250625788]
    for _ in range(20):
        y62 = flow(y62, 0.62, rtol=1e-9)
    rows = [
        ("grazing", grazing(), "closed form of the linear branch"),
        ("neimark-sacker regain",
         root(lambda mu: max(abs(mu)) - 1.0, 0.6180, 0.6192, y62),
         "event-located shooting"),
        ("period doubling",
         root(most_negative_real, 0.738, 0.739, y74), "event-located shooting"),
    ]
    with open("exact_events.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["kind", "omega_rad_s", "method"])
        for kind, om, how in rows:
            w.writerow([kind, f"{om:.10f}", how])
            print(kind, f"{om:.10f}", how)
