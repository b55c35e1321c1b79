//! What the `reproduce` driver alone uses: the jobs it runs ([`jobs`]), when a job may be
//! skipped ([`freshness`]), the answer boxes that open the figure chapters ([`answers`]), the
//! noise-level curve read from the springs jobs' summaries after they ran ([`noise_curve`]) and
//! the book's build ([`book`]).

pub mod answers;
pub mod book;
pub mod freshness;
pub mod jobs;
pub mod noise_curve;
