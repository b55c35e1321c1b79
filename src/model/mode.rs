//! The discrete state of a model: which contacts are engaged and what each circuit is doing.
//!
//! One [`Mode`] serves every model: a device's parts decide how many contacts and circuits it
//! has, and each owns a few bits of the mode. A contact (one stop) is [`Contact::Apart`],
//! [`Contact::Pressed`] into a compliant stop, [`Contact::Clipped`] past a tension-free stop
//! with its force clipped to zero, or [`Contact::Resting`] on a rigid stop after impacts
//! accumulated. A circuit's bits are its own (a bridge's conduction and the velocity's sign
//! since the last extremum, say); [`Mode::circuit`] hands them out unread.

use std::fmt;

/// Most contacts a model may have (two bits each in a [`Mode`]).
pub const MAX_CONTACTS: usize = 16;

/// Most circuits a model may have (eight bits each in a [`Mode`]).
pub const MAX_CIRCUITS: usize = 8;

/// The state of one contact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Contact {
    /// Not touching: no contact force.
    Apart = 0,
    /// Pressed into a compliant stop: the contact force acts.
    Pressed = 1,
    /// Past a tension-free stop with the contact force clipped to zero.
    Clipped = 2,
    /// Resting on a rigid stop, held there by the net force.
    Resting = 3,
}

impl Contact {
    #[inline(always)]
    fn of_bits(b: u64) -> Self {
        match b & 3 {
            0 => Contact::Apart,
            1 => Contact::Pressed,
            2 => Contact::Clipped,
            _ => Contact::Resting,
        }
    }

    /// True unless [`Contact::Apart`].
    #[inline(always)]
    pub fn touching(self) -> bool {
        self != Contact::Apart
    }
}

/// The discrete mode of a model (see the module docs): two bits per contact, eight per
/// circuit.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Mode {
    contacts: u32,
    circuits: u64,
}

impl Mode {
    /// Every contact apart and every circuit's bits zero.
    pub const FREE: Mode = Mode {
        contacts: 0,
        circuits: 0,
    };

    /// The state of contact `k`.
    #[inline(always)]
    pub fn contact(self, k: usize) -> Contact {
        Contact::of_bits((self.contacts >> (2 * k)) as u64)
    }

    /// The same mode with contact `k` in state `c`.
    #[inline(always)]
    #[must_use]
    pub fn with_contact(self, k: usize, c: Contact) -> Mode {
        let shift = 2 * k;
        Mode {
            contacts: (self.contacts & !(3 << shift)) | ((c as u32) << shift),
            circuits: self.circuits,
        }
    }

    /// True while some contact is not apart.
    #[inline(always)]
    pub fn in_contact(self) -> bool {
        self.contacts != 0
    }

    /// The same mode with every contact apart (its circuits' bits kept).
    #[inline(always)]
    #[must_use]
    pub fn without_contacts(self) -> Mode {
        Mode {
            contacts: 0,
            circuits: self.circuits,
        }
    }

    /// The first contact not apart, with its state.
    pub fn touching(self) -> Option<(usize, Contact)> {
        (self.contacts != 0).then(|| {
            let k = (self.contacts.trailing_zeros() / 2) as usize;
            (k, self.contact(k))
        })
    }

    /// The bits of circuit `j`.
    #[inline(always)]
    pub fn circuit(self, j: usize) -> u8 {
        (self.circuits >> (8 * j)) as u8
    }

    /// The same mode with circuit `j`'s bits set to `bits`.
    #[inline(always)]
    #[must_use]
    pub fn with_circuit(self, j: usize, bits: u8) -> Mode {
        let shift = 8 * j;
        Mode {
            contacts: self.contacts,
            circuits: (self.circuits & !(0xff << shift)) | ((bits as u64) << shift),
        }
    }

    /// The same contacts with the circuits' bits of `other`.
    #[inline(always)]
    #[must_use]
    pub fn with_circuits_of(self, other: Mode) -> Mode {
        Mode {
            contacts: self.contacts,
            circuits: other.circuits,
        }
    }
}

impl fmt::Debug for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for k in 0..MAX_CONTACTS {
            let c = self.contact(k);
            if c.touching() {
                write!(f, "{}{c:?}({k})", if first { "" } else { "+" })?;
                first = false;
            }
        }
        if first {
            write!(f, "Free")?;
        }
        if self.circuits != 0 {
            write!(f, " circuits {:#x}", self.circuits)?;
        }
        Ok(())
    }
}

/// What a mode switch is, for counting impacts and booking energy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SwitchKind {
    /// A mass reaches a compliant stop (an impact begins).
    Impact,
    /// A mass bounces off a rigid stop (an impact).
    Rebound,
    /// A mass reaches a rigid stop and comes to rest on it (an impact).
    Stick,
    /// A tension-free contact unloads or re-engages.
    Clip,
    /// A mass leaves a stop.
    Release,
    /// A circuit changes its mode (a bridge starts or stops conducting, a switch acts).
    Circuit,
}

impl SwitchKind {
    /// True for the switches that are impacts.
    pub fn is_impact(self) -> bool {
        matches!(
            self,
            SwitchKind::Impact | SwitchKind::Rebound | SwitchKind::Stick
        )
    }

    /// The kind of a switch seen only by its modes before and after (an observer's view): a
    /// mode unchanged is a rebound off a rigid stop (the one switch that changes only the
    /// state), a change of a contact is that contact's, and a change of the circuits' bits
    /// alone is the circuit's.
    pub fn between(from: Mode, to: Mode) -> Self {
        if from == to {
            return SwitchKind::Rebound;
        }
        let changed = from.contacts ^ to.contacts;
        if changed == 0 {
            return SwitchKind::Circuit;
        }
        let k = (changed.trailing_zeros() / 2) as usize;
        Self::of_contact(from.contact(k), to.contact(k))
    }

    /// The kind of a change of one contact's state from `from` to `to` (a rebound leaves the
    /// contact apart, as it was).
    pub fn of_contact(from: Contact, to: Contact) -> Self {
        match (from, to) {
            (Contact::Apart, Contact::Pressed) => SwitchKind::Impact,
            (Contact::Apart, Contact::Apart) => SwitchKind::Rebound,
            (Contact::Apart, Contact::Resting) => SwitchKind::Stick,
            (Contact::Pressed, Contact::Clipped) | (Contact::Clipped, Contact::Pressed) => {
                SwitchKind::Clip
            }
            _ => SwitchKind::Release,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contacts_and_circuits_keep_their_own_bits() {
        let m = Mode::FREE
            .with_contact(1, Contact::Resting)
            .with_circuit(0, 0x5a)
            .with_circuit(7, 0xff);
        assert_eq!(m.contact(0), Contact::Apart);
        assert_eq!(m.contact(1), Contact::Resting);
        assert_eq!(m.circuit(0), 0x5a);
        assert_eq!(m.circuit(7), 0xff);
        assert_eq!(m.touching(), Some((1, Contact::Resting)));
        let n = m.with_contact(1, Contact::Apart);
        assert!(!n.in_contact());
        assert_eq!(n.circuit(0), 0x5a);
        assert_eq!(m.without_contacts(), n);
        assert_eq!(format!("{m:?}"), "Resting(1) circuits 0xff0000000000005a");
        assert_eq!(format!("{:?}", Mode::FREE), "Free");
    }
}
