//! The modes of an interface circuit: whether its bridge conducts (or which stage of an
//! inductor's transfer runs), and the sign of the velocity since the last displacement
//! extremum, packed into the circuit's bits of a [`crate::model::Mode`]; and what a switch's
//! reset loses.

/// Whether the bridge conducts (bits 0-1 of the circuit's mode bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Bridge {
    /// Blocking (or, with Shockley diodes, always: the law is smooth).
    Off,
    /// Conducting from the element's positive terminal.
    Positive,
    /// Conducting from its negative terminal.
    Negative,
    /// Blocking, with a flyback diode carrying an inductor's current into the storage (a SECE
    /// through its inductor, [`super::sece_inductor`]).
    Flyback,
    /// Blocking, with the element ringing through an inverting inductor (bits 3-4; a
    /// parallel SSHI through its inductor, [`super::sshi_inductor`]).
    Invert {
        /// The element's voltage was negative when the switch closed.
        negative: bool,
        /// The element's voltage has crossed zero.
        returning: bool,
    },
}

/// The bridge states of a bridge with no phases of its own.
pub const BRIDGE_PHASES: [Bridge; 3] = [Bridge::Off, Bridge::Positive, Bridge::Negative];

impl Bridge {
    /// +1, -1, or 0 when off.
    #[inline(always)]
    pub fn sign(self) -> f64 {
        match self {
            Bridge::Off | Bridge::Flyback | Bridge::Invert { .. } => 0.0,
            Bridge::Positive => 1.0,
            Bridge::Negative => -1.0,
        }
    }
}

/// The sign of the velocity since the last extremum (bit 2 of the circuit's mode bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heading {
    /// v >= 0.
    Up,
    /// v < 0.
    Down,
}

impl Heading {
    /// The heading after an extremum.
    #[inline(always)]
    pub fn turned(self) -> Self {
        match self {
            Heading::Up => Heading::Down,
            Heading::Down => Heading::Up,
        }
    }
}

/// The circuit's mode, from and to its bits of a [`crate::model::Mode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CircuitMode {
    /// Bridge conduction.
    pub bridge: Bridge,
    /// Sign of the velocity since the last extremum.
    pub heading: Heading,
}

impl CircuitMode {
    /// The mode of the bits.
    #[inline(always)]
    pub fn of(bits: u8) -> Self {
        Self {
            bridge: match bits & 3 {
                _ if bits & 8 != 0 => Bridge::Invert {
                    negative: bits & 1 != 0,
                    returning: bits & 2 != 0,
                },
                0 => Bridge::Off,
                1 => Bridge::Positive,
                2 => Bridge::Negative,
                _ => Bridge::Flyback,
            },
            heading: if bits & 4 == 0 {
                Heading::Up
            } else {
                Heading::Down
            },
        }
    }

    /// The bits of the mode.
    #[inline(always)]
    pub fn bits(self) -> u8 {
        let b = match self.bridge {
            Bridge::Off => 0,
            Bridge::Positive => 1,
            Bridge::Negative => 2,
            Bridge::Flyback => 3,
            Bridge::Invert {
                negative,
                returning,
            } => 8 | u8::from(negative) | (u8::from(returning) << 1),
        };
        b | if self.heading == Heading::Down { 4 } else { 0 }
    }
}

/// What a switch of the circuit lost (J): in the diodes and in the switch.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ResetLoss {
    /// Diode conduction during a transfer.
    pub diode: f64,
    /// The switch: inversion losses, a converter's inefficiency.
    pub switching: f64,
}
