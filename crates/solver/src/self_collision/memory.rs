//! The skip memory: what the resolution remembers of a box between passes, so that a box
//! provably still clear of pairs within reach is skipped without a look.
//!
//! A box found clear gets an allowance ([`Repulsion::allowance`]): how far each of its points may
//! move, relative to the move of its first point, with every pair still out of reach. Until a
//! point outruns it (or a point enters the box), the box is skipped; skipping it changes no bit.

use super::resolution::Repulsion;

/// What the resolution remembers of a box between passes.
#[derive(Debug, Clone, Copy)]
pub(super) struct Memory {
    /// How far (squared) each of its points may move from its anchor with the box still
    /// certainly clear of pairs within reach (see [`Repulsion::allowance`]); negative when the
    /// box has no anchors.
    pub(super) allowed: f64,
    /// Passes skipped on the current anchors.
    pub(super) skips: u32,
    /// Looks at the box, found clear, before it may take anchors again.
    pub(super) wait: u32,
    /// Anchors lost in a row without having paid for themselves; each doubles the wait.
    pub(super) strikes: u32,
}

impl Memory {
    /// A box the resolution knows nothing of.
    pub(super) const NEW: Self = Self {
        allowed: -1.0,
        skips: 0,
        wait: 0,
        strikes: 0,
    };
}

/// Looks a box that outran its allowance waits before it takes new anchors, at first.
pub(super) const ANCHOR_WAIT: u32 = 4;

/// How far a box's first point may move from its anchor, squared, in squared allowances, with
/// the box still skipped on the other points' moves relative to its move: a thousand
/// allowances (see [`Repulsion::allowance`] for why there is a bound).
pub(super) const FOLLOW2: f64 = 1e6;

/// The most times the wait doubles (to 256 looks).
pub(super) const MAX_STRIKES: u32 = 6;

impl Repulsion {
    /// How far (squared) each point of a box found clear may move from where it is, with the
    /// box still certainly clear, given the smallest squared distance `closest2` between two of
    /// its points; negative when no move is safe.
    ///
    /// Two points that each moved less than `a` are closer than before by less than `2 a` (triangle
    /// inequality), so with `a = (closest - reach) / 2` every pair stays at least `reach` apart,
    /// and [`Repulsion::closest_pair_out_of_reach`] would find the box clear again. A pair's
    /// distance changes only by the difference of its two points' moves, which is unchanged when
    /// the same shift is taken off both: so the moves are measured from the move of the box's first
    /// point. A box carried along by the cloth stays skipped: a falling cloth moves its points
    /// several allowances a step, but a box's points barely against each other. Why that holds in
    /// floating point too: every quantity here and in the displacement test (a squared distance,
    /// its root, a product) is within a few ulps, under 1e-15 relative, of its real value; each
    /// term below is shrunk (or, for the reach, grown) by 1e-12 relative, a thousand times that,
    /// and the 4-ulp margin of `reach2_out` lies well inside it. Taking the shift off a move rounds
    /// in proportion to the moves, not to what is left: the shift is therefore bounded by a
    /// thousand allowances ([`FOLLOW2`]), which keeps that rounding under 2.3e-13 of the allowance,
    /// inside the slack too. So a box skipped by the test is one whose pair test would have found
    /// no pair within reach: skipping it changes nothing, bit for bit.
    #[inline]
    pub(super) fn allowance(&self, closest2: f64) -> f64 {
        const SLACK: f64 = 1e-12;
        let spare = closest2.sqrt() * (1.0 - SLACK) - self.reach * (1.0 + SLACK);
        let each = spare / 2.0 * (1.0 - SLACK);
        // NOTE: finite only: a box with points at infinity (a diverged step) gets no anchors.
        if each > 0.0 && each.is_finite() {
            each * each * (1.0 - SLACK)
        } else {
            -1.0
        }
    }
}
