#!/usr/bin/env python3
"""Prototype 2's capacitor pair behind an ideal full-wave diode bridge: an independent integration.

An outside check of `data/examples/prototype2_bridge.toml`, written from the paper (Le & Halvorsen
2012, eqs 7-10) and textbook circuit laws, not from the endstop library's code. It integrates the
circuit from rest by brute force (no shooting) until the storage has settled, then averages the
DC power and the storage voltage over whole periods, and writes `reference.csv`.

Model (SI units throughout)
---------------------------
Mechanics, eq 7, with the relative displacement x of the proof mass and the base acceleration a:

    m x'' + b x' + km x + Fe + Fim = m a(t),   a(t) = sqrt(2) a_rms g sin(2 pi f t),  g = 9.81

Fim is the end-stop force (eqs 1, 19). The drive used here is small enough that the mass never
reaches the stops (|x| < xmax = 10 um; the script checks max|x| over the whole run and refuses
if it is reached), so the stop law does not enter and is not implemented.

Transducers, eqs 8 and 10: two area-overlap capacitors in anti-phase,

    C1(x) = C0 (1 + x/x0),   C2(x) = C0 (1 - x/x0)      (the paper's "C1/2 = C0 (1 +- x/x0)")

each with the parasitic Cp in parallel. The bias source Vb connects the proof mass (the common
electrode of both transducers) to ground. Fixed electrode i is node i, with voltage V_i measured
to ground; each node goes to ground through the load resistor RL in parallel with the load
capacitor CL (the paper's loads, kept in place behind the bridge). Transducer i's charge (eq 8):

    q_i = (C_i + Cp) (V_i - Vb)

The node charge Q_i = q_i + CL V_i (charge on the plates at node i) is the state; with
D_i = C_i + Cp and S_i = D_i + CL,

    V_i = (Q_i + D_i Vb) / S_i .

Force on the mass (eq 9 with the sign it has in eq 7; the derivative at fixed charge of the
stored energy q_i^2 / (2 D_i)):   -Fe = +1/2 sum_i (V_i - Vb)^2 dC_i/dx,  dC_1,2/dx = +-C0/x0.

Bridge: the two electrode nodes are the bridge's AC terminals; its DC terminals hold the
storage capacitor Cs with the DC load R across it. The storage is floating (neither DC terminal
is grounded), so the bridge is a one-port between node 1 and node 2: with u = V1 - V2 and the
storage voltage Vs, two diodes conduct, each with forward drop VF and zero on-resistance,
  - mode +1 when  u = Vs + 2 VF  and the bridge current i >= 0 (i leaves node 1, enters node 2);
  - mode -1 when -u = Vs + 2 VF  and i >= 0 (i leaves node 2, enters node 1);
  - off otherwise (|u| < Vs + 2 VF, i = 0). Diodes are ideal otherwise (no reverse current,
    no junction capacitance).
Kirchhoff's current law at the nodes and the storage, with s = +1 / -1 / 0 the mode:

    dQ1/dt = -V1/RL - s i,   dQ2/dt = -V2/RL + s i,   Cs dVs/dt = i - Vs/R .

While conducting, Vs = s u - 2 VF is algebraic and i follows from differentiating the
constraint (index reduction): with a_i = (-V_i/RL + C_i' v (Vb - V_i)) / S_i the rate dV_i/dt
without bridge current (dV_i/dt = (dQ_i/dt + C_i' v (Vb - V_i)) / S_i),

    i = (s (a1 - a2) + Vs/(R Cs)) / (1/S1 + 1/S2 + 1/Cs).

Conduction starts when s u - Vs - 2 VF crosses zero upwards (the current it then takes is
checked positive) and ends when i crosses zero downwards; both are located by the integrator's
event finder, and the state is carried over exactly (Vs at exit = s u - 2 VF).

The paper's power is not used here: the quantities are the storage's mean voltage <Vs> and the
DC load's mean power P_DC = <Vs^2>/R, averaged over whole drive periods.

Integration
-----------
Explicit Runge-Kutta DOP853 (scipy.integrate.solve_ivp), rtol 1e-12 with a per-component atol
of rtol times each component's scale (x0, x0 w, 1e-10 C, 1e-10 C, 1 V), one solve_ivp call per
continuous piece (between events and drive-period boundaries, so that the averages are over
whole periods). The system is not stiff without contact (the fastest time constant is
RL (C0 + Cp + CL) ~ 0.2 ms against a 1.5 ms period). Averages come from quadrature components
integrated with the state: int Vs dt and int Vs^2/R dt, and, for an energy ledger that checks
the equations' consistency, the drive's work int m a v dt, the mechanical damping's int b v^2,
the node loads' int (V1^2 + V2^2)/RL and the diodes' int 2 VF i. Over a steady period the
stored energies and the bias source's work (Vb times the net change of the transducer charges)
return to their starting values, so the drive's work equals the sum of the four losses.

From rest (x = v = 0, V1 = V2 = Vs = 0), TRANSIENT_S (2 s, 20 storage time constants R Cs)
of transient rounded up to whole periods, then two successive windows of WINDOW_PERIODS periods;
the reported values are the second window's, and settle_rel_change is the larger of the
relative changes of <Vs^2> and <Vs> between the two windows. Each case is repeated at rtol
1e-11 and 1e-9 to measure the integration error (printed, and written to integration_check.csv
with each run's relative difference from the rtol 1e-12 run): the rtol 1e-11 run's difference
estimates the reported run's error, from above; the 1e-9 run's shows how far DOP853's global
error on this circuit exceeds its rtol (event location included).

Usage:  python independent_pair_bridge.py [--out reference.csv] [--check-out integration_check.csv]
                                         [--device path/to/prototype2_bridge.toml]
"""

import argparse
import csv
import math
import os
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

G = 9.81  # m/s^2, the paper's g

# Parameters: data/examples/prototype2_bridge.toml, key by key (checked against the file below).
P = dict(
    m=1.2e-6,  # [mechanics] mass_kg
    km=21.1,  # [mechanics] stiffness_n_per_m
    b=2.5e-5,  # [mechanics] damping_n_s_per_m
    xmax=10e-6,  # [stops.both] gap_m (only checked: the mass must not reach it)
    C0=1.3e-12,  # [transducer] c0_f
    Cp=7.5e-12,  # [transducer] cp_f
    x0=10e-6,  # [transducer] finger_overlap_m
    RL=15.2e6,  # [transducer] load_resistance_ohm
    CL=5.0e-12,  # [transducer] load_capacitance_f
    Vb=15.0,  # [transducer] bias_v
    Cs=1e-9,  # [interface] storage_capacitance_f
    VF=0.2,  # [interface.diode] forward_drop_v (on_resistance_ohm = 0)
    R=100e6,  # [interface.load] resistance_ohm
)
TOML_KEYS = {
    "m": ("mechanics", "mass_kg"),
    "km": ("mechanics", "stiffness_n_per_m"),
    "b": ("mechanics", "damping_n_s_per_m"),
    "xmax": ("stops", "both", "gap_m"),
    "C0": ("transducer", "c0_f"),
    "Cp": ("transducer", "cp_f"),
    "x0": ("transducer", "finger_overlap_m"),
    "RL": ("transducer", "load_resistance_ohm"),
    "CL": ("transducer", "load_capacitance_f"),
    "Vb": ("transducer", "bias_v"),
    "Cs": ("interface", "storage_capacitance_f"),
    "VF": ("interface", "diode", "forward_drop_v"),
    "R": ("interface", "load", "resistance_ohm"),
}

# (accel_rms_g, freq_hz): the brief's three points at 0.1 g (at 650 and 690 Hz the pair's
# voltage stays below the two diodes' 0.4 V and the bridge never conducts), and three where the
# bridge conducts off resonance, so that the check also sees the conduction away from the peak.
CASES = [(0.1, 650.0), (0.1, 670.0), (0.1, 690.0), (0.1, 680.0), (0.2, 650.0), (0.2, 690.0)]
TRANSIENT_S = 2.0
WINDOW_PERIODS = 50
# The reported run's rtol first; the others measure its integration error (integration_check.csv).
RTOLS = [1e-12, 1e-11, 1e-9]

# State layout: x, v, Q1, Q2, Vs, then quadratures.
IX, IV, IQ1, IQ2, IVS, I_VS, I_PDC, I_DRIVE, I_DAMP, I_RL, I_DIODE = range(11)
NSTATE = 11


def check_device_file(path):
    """Refuses if the device file's values differ from the ones this script integrates."""
    import tomllib

    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    assert doc["transducer"]["kind"] == "area_overlap_pair"
    assert doc["interface"]["kind"] == "full_bridge"
    assert doc["interface"]["diode"]["law"] == "piecewise_linear"
    assert doc["interface"]["diode"]["on_resistance_ohm"] == 0.0
    assert doc["interface"]["load"]["kind"] == "resistor"
    for name, keys in TOML_KEYS.items():
        node = doc
        for k in keys:
            node = node[k]
        if float(node) != P[name]:
            sys.exit(f"{path}: {'.'.join(keys)} = {node}, the script integrates {P[name]}")


class PairBridge:
    """The right-hand side, the events and the mode logic of the circuit in the header."""

    def __init__(self, p, freq_hz, accel_rms_g):
        self.__dict__.update(p)
        self.w = 2.0 * math.pi * freq_hz
        self.amp = math.sqrt(2.0) * accel_rms_g * G
        self.dC1 = self.C0 / self.x0
        self.dC2 = -self.C0 / self.x0

    def nodes(self, y):
        """Node voltages V1, V2 and the node capacitances S1, S2."""
        x = y[IX]
        S1 = self.C0 * (1.0 + x / self.x0) + self.Cp + self.CL
        S2 = self.C0 * (1.0 - x / self.x0) + self.Cp + self.CL
        V1 = (y[IQ1] + (S1 - self.CL) * self.Vb) / S1
        V2 = (y[IQ2] + (S2 - self.CL) * self.Vb) / S2
        return V1, V2, S1, S2

    def bridge_current(self, s, y, V1, V2, S1, S2):
        """The conducting bridge's current i (>= 0 while it conducts) and the storage voltage."""
        v = y[IV]
        Vs = s * (V1 - V2) - 2.0 * self.VF
        a1 = (-V1 / self.RL + self.dC1 * v * (self.Vb - V1)) / S1
        a2 = (-V2 / self.RL + self.dC2 * v * (self.Vb - V2)) / S2
        i = (s * (a1 - a2) + Vs / (self.R * self.Cs)) / (1.0 / S1 + 1.0 / S2 + 1.0 / self.Cs)
        return i, Vs

    def rhs(self, s):
        def f(t, y):
            x, v = y[IX], y[IV]
            V1, V2, S1, S2 = self.nodes(y)
            if s == 0:
                i, Vs = 0.0, y[IVS]
                dVs = -Vs / (self.R * self.Cs)
            else:
                i, Vs = self.bridge_current(s, y, V1, V2, S1, S2)
                dVs = 0.0  # Vs is algebraic while conducting; the state's copy is set at exit
            a = self.amp * math.sin(self.w * t)
            fe = 0.5 * ((V1 - self.Vb) ** 2 * self.dC1 + (V2 - self.Vb) ** 2 * self.dC2)
            acc = (-self.b * v - self.km * x + fe) / self.m + a
            dy = np.empty(NSTATE)
            dy[IX] = v
            dy[IV] = acc
            dy[IQ1] = -V1 / self.RL - s * i
            dy[IQ2] = -V2 / self.RL + s * i
            dy[IVS] = dVs
            dy[I_VS] = Vs
            dy[I_PDC] = Vs * Vs / self.R
            dy[I_DRIVE] = self.m * a * v
            dy[I_DAMP] = self.b * v * v
            dy[I_RL] = (V1 * V1 + V2 * V2) / self.RL
            dy[I_DIODE] = 2.0 * self.VF * i
            return dy

        return f

    def events(self, s):
        if s == 0:

            def on_plus(t, y):
                V1, V2, _, _ = self.nodes(y)
                return (V1 - V2) - y[IVS] - 2.0 * self.VF

            def on_minus(t, y):
                V1, V2, _, _ = self.nodes(y)
                return (V2 - V1) - y[IVS] - 2.0 * self.VF

            for e in (on_plus, on_minus):
                e.terminal, e.direction = True, 1.0
            return [on_plus, on_minus]

        def off(t, y):
            V1, V2, S1, S2 = self.nodes(y)
            return self.bridge_current(s, y, V1, V2, S1, S2)[0]

        off.terminal, off.direction = True, -1.0
        return [off]


def run(freq_hz, accel_rms_g, rtol):
    """From rest to the end of the second window; returns the two windows' averages."""
    c = PairBridge(P, freq_hz, accel_rms_g)
    period = 1.0 / freq_hz
    n_transient = math.ceil(TRANSIENT_S / period)
    n_total = n_transient + 2 * WINDOW_PERIODS
    scale = np.array([c.x0, c.x0 * c.w, 1e-10, 1e-10, 1.0, 1, 1, 1, 1, 1, 1], dtype=float)
    atol = rtol * scale
    # Quadratures: their atol is set relative to one period's value at about 1 V and 1 uW.
    atol[I_VS] = rtol * 1.0 * period
    atol[I_PDC:] = rtol * 1e-6 * period

    y = np.zeros(NSTATE)
    y[IQ1] = -(c.C0 + c.Cp) * c.Vb  # V1 = 0 at x = 0
    y[IQ2] = -(c.C0 + c.Cp) * c.Vb  # V2 = 0
    mode = 0
    t = 0.0
    marks = {}  # period index -> state at its start
    max_abs_x = 0.0
    n_events = 0
    for k in range(n_total):
        t_end = (k + 1) * period
        while t < t_end * (1.0 - 1e-15):
            sol = solve_ivp(
                c.rhs(mode), (t, t_end), y, method="DOP853", rtol=rtol, atol=atol,
                events=c.events(mode), dense_output=False,
            )
            if sol.status < 0:
                raise RuntimeError(sol.message)
            max_abs_x = max(max_abs_x, float(np.max(np.abs(sol.y[IX]))))
            if sol.status == 1:  # an event
                hit = [j for j, te in enumerate(sol.t_events) if len(te)]
                j = hit[0]
                t = float(sol.t_events[j][0])
                y = sol.y_events[j][0].copy()
                n_events += 1
                V1, V2, S1, S2 = c.nodes(y)
                if mode == 0:
                    s = 1 if j == 0 else -1
                    i, _ = c.bridge_current(s, y, V1, V2, S1, S2)
                    if i <= 0.0:
                        raise RuntimeError(f"entry at t = {t} with bridge current {i} <= 0")
                    mode = s
                else:
                    y[IVS] = mode * (V1 - V2) - 2.0 * c.VF
                    mode = 0
            else:
                t = t_end
                y = sol.y[:, -1].copy()
        if k + 1 in (n_transient, n_transient + WINDOW_PERIODS, n_total):
            yy = y.copy()
            if mode != 0:  # the storage voltage is algebraic while conducting
                V1, V2, _, _ = c.nodes(yy)
                yy[IVS] = mode * (V1 - V2) - 2.0 * c.VF
            marks[k + 1] = yy

    if max_abs_x >= c.xmax:
        raise RuntimeError(f"max |x| = {max_abs_x} reaches the stop at {c.xmax}: stops not modelled")

    def window(a, b):
        ya, yb = marks[a], marks[b]
        dur = (b - a) * period
        d = (yb - ya) / dur
        ledger_in = d[I_DRIVE]
        ledger_out = d[I_DAMP] + d[I_RL] + d[I_DIODE] + d[I_PDC]
        return dict(
            p_dc_w=d[I_PDC],
            vdc_v=d[I_VS],
            ledger_rel=(ledger_in - ledger_out) / ledger_in,
            vs_end=yb[IVS],
        )

    w1 = window(n_transient, n_transient + WINDOW_PERIODS)
    w2 = window(n_transient + WINDOW_PERIODS, n_total)
    def rel_change(key):
        # Both windows exactly zero (a bridge that never conducted): no change.
        d = abs(w2[key] - w1[key])
        return 0.0 if d == 0.0 else d / abs(w2[key])

    settle = max(rel_change("p_dc_w"), rel_change("vdc_v"))
    return dict(w2, settle_rel_change=settle, max_abs_x_m=max_abs_x, n_events=n_events,
                periods=n_total)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="reference.csv")
    ap.add_argument("--check-out", default="integration_check.csv")
    ap.add_argument("--device", default=None, help="device file to check the parameters against")
    args = ap.parse_args()
    if args.device:
        check_device_file(args.device)

    rows, checks = [], []
    for g, f in CASES:
        runs = {}
        for rtol in RTOLS:
            t0 = time.time()
            runs[rtol] = run(f, g, rtol)
            runs[rtol]["seconds"] = time.time() - t0
        r = runs[RTOLS[0]]
        print(
            f"{g:g} g, {f:.0f} Hz: P_DC = {r['p_dc_w']:.12e} W, <Vs> = {r['vdc_v']:.12e} V, "
            f"settle {r['settle_rel_change']:.2e}, ledger {r['ledger_rel']:.2e}, "
            f"max|x| = {r['max_abs_x_m'] * 1e6:.4f} um, {r['n_events']} events, "
            f"{r['periods']} periods, {r['seconds']:.1f} s",
            flush=True,
        )
        rows.append((f, g, r["p_dc_w"], r["vdc_v"], r["settle_rel_change"]))
        for rtol, q in runs.items():

            def rel(key):
                return abs(q[key] - r[key]) / abs(r[key]) if r[key] else abs(q[key])

            print(f"    rtol {rtol:.0e}: P_DC differs by {rel('p_dc_w'):.2e}, <Vs> by "
                  f"{rel('vdc_v'):.2e} ({q['seconds']:.1f} s)", flush=True)
            checks.append((f, g, rtol, q["p_dc_w"], q["vdc_v"], rel("p_dc_w"), rel("vdc_v"),
                           q["settle_rel_change"], q["ledger_rel"], q["max_abs_x_m"],
                           q["n_events"], q["seconds"]))

    tmp = args.out + ".tmp"
    with open(tmp, "w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["freq_hz", "accel_rms_g", "p_dc_w", "vdc_v", "settle_rel_change"])
        for row in rows:
            wr.writerow([f"{row[0]:g}", f"{row[1]:g}", repr(float(row[2])), repr(float(row[3])),
                         f"{row[4]:.3e}"])
    os.replace(tmp, args.out)
    tmp = args.check_out + ".tmp"
    with open(tmp, "w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["freq_hz", "accel_rms_g", "rtol", "p_dc_w", "vdc_v", "p_rel_diff",
                     "v_rel_diff", "settle_rel_change", "ledger_rel_residual", "max_abs_x_m",
                     "bridge_events", "seconds"])
        for c in checks:
            wr.writerow([f"{c[0]:g}", f"{c[1]:g}", f"{c[2]:.0e}", repr(float(c[3])),
                         repr(float(c[4])), f"{c[5]:.3e}", f"{c[6]:.3e}", f"{c[7]:.3e}",
                         f"{c[8]:.3e}", repr(float(c[9])), c[10], f"{c[11]:.1f}"])
    os.replace(tmp, args.check_out)


if __name__ == "__main__":
    main()
