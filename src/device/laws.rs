//! The force laws of [`crate::laws`] built from a device's descriptions: a stop's contact law
//! and model from its `[stops]` table (and a device's two), and a Hertz line law from a
//! `hertz_line` stop.

use super::{Device, HertzLineStop, Stop, StopLaw};
use crate::laws::contact::{ContactDamping, ContactLaw, StopModel};
use crate::laws::hertz::HertzLine;

impl Device {
    /// The models of the upper and the lower stop, each if present.
    pub fn stop_models(&self) -> (Option<StopModel>, Option<StopModel>) {
        (
            self.stops.upper.as_ref().map(StopModel::of),
            self.stops.lower.as_ref().map(StopModel::of),
        )
    }
}

impl HertzLine {
    /// The contact law of a Hertz line stop (t, R, E, nu).
    pub fn of_stop(s: &HertzLineStop) -> Self {
        Self {
            length_m: s.contact_length_m,
            radius_m: s.bump_radius_m,
            lambda_per_pa: (1.0 - s.poisson_ratio * s.poisson_ratio)
                / (std::f64::consts::PI * s.youngs_modulus_pa),
        }
    }

    /// The Hertz line law of a device's first Hertz line stop (upper, then lower), if it
    /// has one.
    pub fn of_device(device: &Device) -> Option<Self> {
        device.stops.present().find_map(|(_, s)| match &s.law {
            StopLaw::HertzLine(h) => Some(Self::of_stop(h)),
            _ => None,
        })
    }
}

impl ContactLaw {
    /// The law of a Hertz line stop: eq 6, or eq 19's linear fit.
    pub fn of_hertz_line(h: &HertzLineStop) -> Self {
        if h.linear_fit {
            ContactLaw::Linear(h.linear_stiffness_n_per_m())
        } else {
            ContactLaw::Hertz(HertzLine::of_stop(h))
        }
    }
}

impl StopModel {
    /// The model of a stop description.
    pub fn of(stop: &Stop) -> Self {
        let gap = stop.gap_m;
        let viscous = ContactDamping::Viscous(stop.damping_n_s_per_m);
        let compliant = |law| StopModel::Compliant {
            gap,
            law,
            damping: viscous,
            tension_free: stop.tension_free,
        };
        match &stop.law {
            StopLaw::HertzLine(h) => compliant(ContactLaw::of_hertz_line(h)),
            StopLaw::Linear { stiffness_n_per_m } => {
                compliant(ContactLaw::Linear(*stiffness_n_per_m))
            }
            StopLaw::HertzPoint(k) => compliant(ContactLaw::Power {
                k: k.value(),
                n: 1.5,
            }),
            StopLaw::HuntCrossley {
                stiffness_n_per_m_pow_n,
                exponent,
                damping_s_per_m,
            } => StopModel::Compliant {
                gap,
                law: ContactLaw::Power {
                    k: *stiffness_n_per_m_pow_n,
                    n: *exponent,
                },
                damping: ContactDamping::HuntCrossley(*damping_s_per_m),
                tension_free: true,
            },
            StopLaw::Restitution { coefficient } => StopModel::Rigid {
                gap,
                restitution: *coefficient,
            },
        }
    }
}
