//! The bridge's linearisation: the Jacobian of its element's and storage's rates and of the
//! force on the mass in each conduction mode (by hand for the piezoelectric element and the
//! coil, by central differences for the electrostatic pair).

use nalgebra::{SMatrix, SVector};

use super::bridge::Circuit;
use super::element::Element;
use super::mode::Bridge;
use super::parts::DiodeLaw;

impl Circuit {
    /// The bridge and its element's part of the Jacobian in a bridge mode (see
    /// [`Circuit::jacobian`]).
    pub(super) fn bridge_jacobian<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        let gl = self.sink_conductance();
        let cs = self.cs;
        let (e, ivs) = (self.e, self.vs);
        match self.element {
            Element::Piezo { theta, cp } => {
                j[(1, e)] += theta / m;
                let open_v = -theta / cp;
                let set_open = |j: &mut SMatrix<f64, N, N>| {
                    j[(e, 1)] = open_v;
                    j[(ivs, ivs)] = -gl / cs;
                };
                if !self.bridge_between_extrema() {
                    set_open(j);
                    return;
                }
                match self.diode {
                    DiodeLaw::Shockley { is, nvt } => {
                        // path current I_s (exp(u / 2nVT) - 1), u1 = Vp - Vs, u2 = -Vp - Vs.
                        let d = |u: f64| is / (2.0 * nvt) * (u / (2.0 * nvt)).exp();
                        let (d1, d2) = (d(y[e] - y[ivs]), d(-y[e] - y[ivs]));
                        // i1 - i2 and i1 + i2 in (Vp, Vs).
                        let diff = (d1 + d2, -d1 + d2);
                        let sum = (d1 - d2, -d1 - d2);
                        j[(e, 1)] = open_v;
                        j[(e, e)] = -diff.0 / cp;
                        j[(e, ivs)] = -diff.1 / cp;
                        j[(ivs, e)] = sum.0 / cs;
                        j[(ivs, ivs)] = (sum.1 - gl) / cs;
                    }
                    DiodeLaw::PiecewiseLinear { ron, .. } => match bridge {
                        Bridge::Off => set_open(j),
                        b => {
                            let s = b.sign();
                            if ron == 0.0 {
                                let (dv, dvs) = (-s * theta / (cp + cs), -gl / (cp + cs));
                                j[(e, 1)] = dv * s;
                                j[(e, ivs)] = dvs * s;
                                j[(ivs, 1)] = dv;
                                j[(ivs, ivs)] = dvs;
                            } else {
                                let (die, divs) = (s / (2.0 * ron), -1.0 / (2.0 * ron));
                                j[(e, 1)] = open_v;
                                j[(e, e)] = -die * (s / cp);
                                j[(e, ivs)] = -divs * (s / cp);
                                j[(ivs, e)] = die / cs;
                                j[(ivs, ivs)] = (divs - gl) / cs;
                            }
                        }
                    },
                }
            }
            Element::Coil { phi, rc, l } => {
                let s = bridge.sign();
                let rpath = rc + 2.0 * self.ron();
                // The coil current's gradient in (v, I, Vs).
                let di = if l > 0.0 {
                    [0.0, 1.0, 0.0]
                } else if bridge == Bridge::Off {
                    [0.0; 3]
                } else {
                    [phi / rpath, 0.0, -s / rpath]
                };
                let cols = [1, e, ivs];
                for (k, &c) in cols.iter().enumerate() {
                    j[(1, c)] += di[k] * -phi / m;
                }
                if l > 0.0 && bridge != Bridge::Off {
                    let src = [phi, 0.0, -s];
                    for (k, &c) in cols.iter().enumerate() {
                        j[(e, c)] = (src[k] - di[k] * rpath) / l;
                    }
                } else if l > 0.0 {
                    j[(e, e)] = -rpath / l;
                }
                for (k, &c) in cols.iter().enumerate() {
                    let gl_k = if c == ivs { gl } else { 0.0 };
                    j[(ivs, c)] = (di[k] * s - gl_k) / cs;
                }
            }
            Element::Pair(_) => self.pair_jacobian(bridge, y, m, sc, j),
        }
    }

    /// The pair's part of the Jacobian, by central differences of the circuit's force and
    /// rates in the state's scaled coordinates: the port's equations are smooth in each mode,
    /// and their derivatives by hand would repeat the node voltages' quotient rule for every
    /// diode law; the monodromy they feed is checked against differences of the period map.
    fn pair_jacobian<const N: usize>(
        &self,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        let rows = [self.e, self.e + 1, self.vs];
        let eval = |z: &SVector<f64, N>| {
            let mut r = SVector::<f64, N>::zeros();
            let f = self.force_and_rates(bridge, z, &mut r);
            (f, r)
        };
        for c in [0, 1, self.e, self.e + 1, self.vs] {
            // Steps of 1e-6 of each scale: truncation ~1e-12 and rounding ~1e-10 of a row.
            let h = 1e-6 * sc[c];
            let (mut yp, mut ym) = (*y, *y);
            yp[c] += h;
            ym[c] -= h;
            let ((fp, rp), (fm, rm)) = (eval(&yp), eval(&ym));
            j[(1, c)] += (fp - fm) / (2.0 * h) / m;
            for &r in &rows {
                j[(r, c)] = (rp[r] - rm[r]) / (2.0 * h);
            }
        }
    }
}
