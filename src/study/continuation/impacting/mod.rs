//! Every branch of periodic orbits of a device whose stops are rigid (restitution), with the
//! bifurcations at which they meet: the bifurcation diagram in one drive parameter.
//!
//! # Why a device with rigid stops needs its own continuation
//! At a rigid stop the flow is reset, not deformed: as an impacting orbit approaches grazing
//! its impact speed u vanishes and the saltation matrix of the impact grows like 1/u, so its
//! Floquet multipliers diverge (Nordmark's square-root grazing map; di Bernardo et al.,
//! *Piecewise-smooth Dynamical Systems*, 2008, chapters 2 and 4). On the period map the
//! branch is then no longer differentiable: the domain in which Newton's method converges
//! shrinks like u^2, pseudo-arclength steps collapse before the grazing is reached, and the
//! jump of the multipliers across it, from the non-impacting orbit's to the impacting one's,
//! looks like a smooth bifurcation if it is tested for as one. Here each impacting orbit is
//! instead the solution of a boundary-value problem whose unknowns are its impacts' phases and
//! states ([`ImpactSequence`], the file `bvp.rs`): smooth in the impact speeds through zero, so
//! that a branch reaches its grazing as an ordinary point, with the speed falling linearly to
//! zero, and its multipliers are computed from its own saltation and transition matrices.
//!
//! # What meets at a grazing
//! A grazing is where an orbit touches a stop with zero velocity. It is not a smooth
//! bifurcation and no fold, period doubling or branch point is located across it: it is the
//! point at which a branch of orbits with one more impact begins (or ends), and at which the
//! multipliers jump. The diagram is built outwards from the non-impacting branch (followed on
//! the device without its stops, which is smooth through the grazing and whose orbits beyond
//! it are virtual):
//!
//! 1. every grazing of the non-impacting orbit starts the branch of orbits with one impact at
//!    each stop it grazes, and, for a device symmetric under x -> -x grazing both stops at
//!    once, the symmetric branch with an impact at each (followed on its half-period map);
//! 2. a branch ends where an impact speed falls to zero (the orbit without that impact takes
//!    over, or the non-impacting one) or where a flight reaches a stop (the orbit with one
//!    impact more begins there): each end starts the branch it meets, unless a branch already
//!    followed passes there;
//! 3. a multiplier of a symmetric orbit's half-period map through -1 is a symmetry-breaking
//!    pitchfork: the two mirror-image asymmetric branches start there, and each ends where it
//!    returns to the symmetric orbits;
//! 4. a multiplier through -1 of the period map is a period doubling: optionally the
//!    period-two branch starts there ([`DiagramSettings::period_two`]).
//!
//! Smooth events are located only between two points of one branch ([`EventKind`]).
//!
//! # Files
//! `segment.rs` integrates one flight with its variational equations, `bvp.rs` poses the
//! boundary-value problem of an impact sequence, `follow.rs` continues one branch with its
//! events, `build.rs` builds the whole diagram from the non-impacting branch (its types are
//! those of the parent's `diagram_types.rs`), and `starts.rs` makes the starts of new branches.

mod build;
pub(super) mod bvp;
mod follow;
mod segment;
mod starts;

pub use build::{rigid_diagram, DiagramSettings};
pub use bvp::{Closure, ImpactSequence};

use super::diagram_types::{
    BranchEnd, BranchKind, Diagram, DiagramBranch, DiagramEvent, DiagramPoint, EndKind, EventKind,
};
