//! The conformance kit of clothsim: any solver, given by its [`SolverEntry`](cloth_solver::SolverEntry) and options, run
//! on the same cases and held to the same measures as the course's Verlet.
//!
//! ```no_run
//! let report = cloth_check::check(
//!     &cloth_solver::Verlet::ENTRY,
//!     &serde_json::json!({}),
//!     &cloth_check::CheckOptions::default(),
//! )?;
//! print!("{report}");
//! assert!(report.passed());
//! # Ok::<(), cloth_check::CheckError>(())
//! ```
//!
//! [`check`] returns a [`Report`]: one [`CaseReport`] per case, each measure with its value,
//! bound and outcome; it prints as a table and serialises to JSON. [`frames_as_text`] gives a
//! scene's frames under a solver as text, for a solver crate's own snapshot test.
//!
//! # Measures
//!
//! Each measure is computed during the run, from the state at the end of every frame; `H` is
//! the total energy: kinetic (from the step velocity `(x - x_last) / dt`, which is the motion a
//! solver hands the next step) plus the energy of every enabled spring (`k (l - rest)^2 / 2`,
//! `k = ks`, or `0.2 ks` for bending) plus the scene's gravity (`-m g . x`). The energy scale
//! is `E = M |g| L`: the cloth's mass, gravity's magnitude and the cloth's longest side, the
//! energy of a fall of the cloth's own size (1470 J for the course's cloth).
//!
//! - **finite** (`finite`, seconds): every position stays finite and no step fails. A
//!   non-finite state is a blow-up, never physics.
//! - **pins** (`pins`, count of pinned points that moved): pinned points never move, to the
//!   bit. The model holds them fixed; a pin that creeps by rounding is a pin that is not held.
//! - **energy peak** (`energy peak`, J): `H` never exceeds `H(0)` by more than 0.1 % of `E`.
//!   Nothing in the model adds energy: gravity is conservative and counted in `H`, the drag
//!   and friction only take energy out, the collisions and the stretch limit are constraints
//!   that do no work, and a step that lands on a lower `H` than it started from cannot pass
//!   `H(0)` later without a source. 0.1 % of `E` is room for the step velocity's lag (the
//!   kinetic energy is measured half a step behind the positions) and rounding; a solver that
//!   pumps energy passes it within a few frames of starting to.
//! - **energy rise** (`energy rise`, J): the sum of the rises of `H` from frame to frame after
//!   2 s is at most 0.1 % of `E` or three times Verlet's own on the same case, whichever is
//!   larger. After 2 s the cloth has fallen and caught; what moves it then is the last of its
//!   swing and the jitter of contacts, and `H` can only go down but for the noise of the
//!   contacts (a point put back outside an object gains the offset's potential energy), which
//!   the reference shows in its own figure. A solver whose step pushes energy back in each
//!   frame (a contact response that overshoots, a constraint solved to a point above its
//!   start) sums rises of many times that.
//! - **stretch** (`stretch`, a ratio), only with the limit on: the largest spring length over
//!   rest after 1 s is at most 1.122 or 1.02 times Verlet's own largest on the same case,
//!   whichever is larger. The limit holds springs at 1.1 rest at the end of each step; the
//!   course's one sequential sweep leaves a few per cent over that where springs share points,
//!   as Verlet shows, and 1.122 is 2 % of room above the limit for any solver. After 1 s, so
//!   that the catch of the fall (a transient the course's sweep also lets through) is over.
//! - **settle** (`settle`, m/s): on scenes without contact (pinned2, pinned4, hammock,
//!   curtain) the RMS point speed at 4 s, from the step velocity, is under 1 cm/s: the course's
//!   drag (5.4 1/s) takes any motion down by e^-21 in 4 s, so what remains is motion the solver
//!   keeps up. On scenes with contact the mean over the last second of the RMS point speed over
//!   each frame (a point's displacement over the frame's duration: the step velocity of a
//!   resting point swings with the collision offset at every step) is under 2 cm/s. Either
//!   bound gives way to three times the largest of Verlet's own figure at `ks` x {1, 1 - 2e-4,
//!   1 + 2e-4} where that is larger: cloth on a sphere or in folds creeps against friction for
//!   seconds in the model itself, and cloth whose layers touch (pinned2 hanging 3.3 times
//!   stretched with the limit off folds onto itself) jitters under self-collision's pushes, by
//!   bursts whose timing turns on rounding; the bound is then the reference's own motion, taken
//!   over perturbations of the case so that it does not hang on where one run happens to be.
//! - **swap to**, **swap back**, **edit** (change of the kinetic energy, as a share of the
//!   motion's energy): from Verlet's run at frames 10, 20 and 40 of pinned4 and sphere
//!   (falling, catching, rebounding or in contact), the solver takes over at its own steps per
//!   frame and its kinetic energy after its first frame is within 5 % of the motion's energy
//!   (kinetic plus elastic, at the swap) of what Verlet reaches at the same frame; handed back
//!   to Verlet after that frame, Verlet's first frame is within 5 % of the solver's own next
//!   one; and the solver with its steps per frame edited to one more is within 5 % of itself
//!   unedited. One frame of the same cloth under two good integrators differs by their
//!   truncation, a few per cent of the energy in motion at most; a solver that loses the
//!   velocity the state carries (or reads it over the wrong step) is off by its whole kinetic
//!   energy or by the square of the steps' ratio. The share is of the motion's energy rather
//!   than of the kinetic energy itself because at a swing's turning point the kinetic energy is
//!   a few per cent of the motion's, and the same truncation is then tens of per cent of it.
//!   Every swap and edit rescales the previous positions with
//!   [`ClothState::retime`](cloth_mesh::ClothState::retime).
//! - **wind** (`wind`, relative difference): the curtain, self-collision off, under a 10 m/s
//!   wind across it for 3 s at the solver's own steps per frame: how far its centre goes
//!   downwind is within 5 % of how far it goes under Verlet at the course's steps. The run
//!   applies the wind between steps through the previous positions, as it applies a hand, so
//!   every solver feels the same push; after 3 s of the course's drag (a swing down by e^-16)
//!   the curtain hangs where wind, gravity and springs balance, a state of the model and not of
//!   the integrator. A solver that loses the velocity
//!   handed to it between steps, or reads it over the wrong step, hangs where there is no wind
//!   or off by the steps' ratio.
//! - **time** (`time`, s): the case's wall-clock time is within its budget (below).
//!
//! Verlet's figures that the bounds scale with are constants of the tree, written by the
//! ignored generator `write_verlet_figures` (`CLOTH_CHECK_WRITE_FIGURES=1 cargo test -p
//! cloth-check --release -- --ignored write_verlet_figures`), so a check never runs Verlet's
//! reference. Verlet runs each case at
//! the course's 30 steps per frame, or at more where `ks` asks for them (200 at 1e6 N/m, in
//! proportion to `sqrt(ks)`: an explicit step's stable size goes as `sqrt(m / k)`), with its
//! damping and friction retimed to keep their rates.
//!
//! # Cases
//!
//! Every case runs a bundled scene from rest for 4 s of simulated time (360 frames at 90 per
//! second).
//!
//! - The quick set (the default): all eight bundled scenes at the solver's recommended steps
//!   per frame ([`SolverEntry::steps_per_frame`](cloth_solver::SolverEntry::steps_per_frame)) and at 2, with the stretch limit on and off
//!   (self-collision as the scene has it); at ks 1e5 and 1e6 N/m at one step per frame with
//!   the limit on; and the swap cases of pinned4 and sphere at frames 10, 20 and 40.
//! - The full set ([`CheckOptions::full`]): steps 1, 2, 5, 10 and 30 as well as the solver's
//!   own, and each case with self-collision on and off. For nightly runs.
//!
//! A case beyond an explicit solver's declared stability
//! ([`SolverEntry::is_explicit`](cloth_solver::SolverEntry::is_explicit), `ks` above
//! [`StepParams::explicit_ks_limit`](cloth_mesh::StepParams::explicit_ks_limit) at the case's
//! step) is skipped: the solver says it cannot run it, which is not a failure.
//!
//! # Budgets
//!
//! Each case may take forty times Verlet's time on the same case (at Verlet's steps per frame
//! for its `ks`) plus five seconds; a run past its budget is stopped there and the case fails as
//! too slow, so a check takes a bounded time whatever the solver. Verlet's time is measured when
//! the check starts, on the same machine: the fastest of three runs of three frames of each
//! scene, scaled to the case's steps and frames. Those first frames are the cheapest (Verlet's
//! own whole runs take two to eleven times what they predict), hence the generous multiple.
//! Cases run on one thread per core ([`CheckOptions::threads`]); the calibration runs alone
//! before them.
//!
//! # Expected failures
//!
//! What solvers fail today is listed beside the kit in `expected-failures.json`: solver, case,
//! measure and the figure it failed with. A listed measure that fails is an expected failure
//! and does not fail the check; a listed measure that passes fails the check ("passes now:
//! remove it from the list"), so the list can only shrink. [`Report::to_expected`] gives a
//! report's failures in the list's form.

mod case;
mod energy;
mod error;
mod expected;
mod figures;
mod frames;
mod kit;
mod measure;
mod report;
mod stepper;

pub use case::{FULL_STEPS, STIFF_KS, SWAP_FRAMES, SWAP_SCENES};
pub use error::CheckError;
pub use expected::ExpectedFailure;
pub use figures::KS_PERTURBATIONS;
pub use frames::{FramesSpec, frames_as_text};
pub use kit::{
    BUDGET_FLOOR, BUDGET_MULTIPLE, CONTACT_SPEED, CheckOptions, EDIT, ENERGY_PEAK, ENERGY_RISE,
    FINITE, PEAK_SHARE, PINS, RISE_SHARE, RISE_VERLET_FACTOR, SETTLE, SETTLE_VERLET_FACTOR,
    SETTLED_SPEED, STRETCH, STRETCH_BOUND, STRETCH_VERLET_FACTOR, SWAP_BACK, SWAP_SHARE, SWAP_TO,
    TIME, check, check_each,
};
pub use measure::{RISE_FROM_SECONDS, RUN_SECONDS, SETTLE_SPAN_SECONDS, STRETCH_FROM_SECONDS};
pub use report::{CaseReport, Measure, Outcome, Report, Verdict};
