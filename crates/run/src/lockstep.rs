//! Runs stepped in lockstep on a thread of their own, against the wall clock: what the live UI
//! steps, a single cloth being a lockstep of one.
//!
//! A [`Lockstep`] owns one [`Run`] per variant and one clock for the group: while running it
//! owes `wall * rate` simulated seconds and pays them a frame at a time (an accumulator of
//! `1 / frames_per_sec` of the first variant that has not stopped). A frame is [`advance`]:
//! every variant that has not stopped steps to the end of frame k, each on its own state and
//! solver, on up to as many threads as asked (`std::thread::scope`, the threads taking the next
//! unstepped variant as each finishes), and frame k + 1 starts only when every variant has ended
//! frame k. The headless study steps its variants through the same [`advance`]. The group's
//! budget is one clock: what the variants together cannot pay within [`MAX_DEBT`] of wall time
//! is forgiven and reported as lagging, so the group runs below real time as one, its variants
//! never apart.
//!
//! Commands (pause, run, a single frame, reset) act on every variant; edits of the settings and
//! the solver go to one variant ([`Lockstep::send_to`]), since each keeps its own varied values.
//! A command leaves the frame in progress between two steps: a reset discards it, an edit takes
//! effect and the frame goes on, a pause takes effect when the frame in progress has ended. So
//! several variants are published, and seen, only at frame boundaries, all at the same frame; a
//! single cloth is published between any two steps when the UI wants a snapshot, so a cloth
//! whose frame takes seconds still moves on screen. A variant that diverges stops alone (its
//! run keeps its fault) and the others go on; a stopped variant waits for a reset, so it never
//! has to catch up with the group (a single cloth may go on anyway, since it has no group to
//! keep up with).
//!
//! The UI asks for a snapshot when it is ready to draw ([`Lockstep::adopt_into`]); the thread
//! publishes one when asked (and at once after a stop or a single frame), swapping position
//! buffers rather than allocating, so a big cloth costs one copy per drawn frame. Nothing here
//! knows of the terminal.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use crate::{Command, Run};

/// Most wall time of owed simulation kept; beyond it the debt is forgiven (lagging).
///
/// NOTE: a quarter second keeps a brief hiccup (a slow draw, a busy machine) from losing
/// simulated time, yet a cloth that cannot keep up falls at most this far behind.
pub const MAX_DEBT: Duration = Duration::from_millis(250);

/// How often the rates are measured.
const WINDOW: Duration = Duration::from_secs(1);

/// Longest a paused worker sleeps before looking at its stop flag again.
const IDLE: Duration = Duration::from_millis(500);

/// How fast a worker runs, measured over about a second of wall time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Rates {
    /// Simulated seconds per wall second, over the rate asked for (1 = keeping up).
    pub realtime_factor: f64,
    /// Solver steps per wall second.
    pub steps_per_sec: f64,
    /// Whether owed time was dropped because the steps could not keep up, and the window
    /// ran below the rate asked for.
    pub lagging: bool,
    /// Whether the figures are measured (false until a second has passed since a change).
    pub measured: bool,
}

/// What the UI learns from a snapshot besides the cloth itself.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Adopted {
    /// Whether simulated time advances (a stop pauses it).
    pub running: bool,
    /// Errors of commands, for the message line.
    pub errors: Vec<String>,
    /// The latest rates.
    pub rates: Rates,
}

/// One cloth's part of a snapshot: everything the UI shows of a running simulation, which its
/// mirror (the UI's copy) takes in.
#[derive(Debug, Default)]
struct Cloth {
    /// Positions at the end of the last step taken.
    positions: Vec<cloth_solver::Vec3>,
    time: f64,
    steps: u64,
    frames: u64,
    history: std::collections::VecDeque<crate::Sample>,
    /// Rows of the stepping side's record not yet adopted, which start at this index of it.
    rows_from: usize,
    new_rows: Vec<crate::export::StatsRow>,
    peak_kinetic: f64,
    fault: Option<crate::Fault>,
    /// The scene, when a hand's pin or cut (or a reset after one) changed it since the last
    /// snapshot: the mirror draws the mesh the thread steps.
    scene: Option<std::sync::Arc<cloth_scene::Scene>>,
    /// The touches applied since the start or the last reset, when they changed.
    touched: Option<Vec<crate::Timed>>,
    /// The point the hand holds.
    held: Option<crate::Held>,
}

impl Cloth {
    /// Moves this snapshot into `mirror`, whose settings, scene and solver the UI owns.
    pub fn adopt_into(&mut self, mirror: &mut Run) {
        std::mem::swap(&mut mirror.state.positions, &mut self.positions);
        mirror.time = self.time;
        mirror.steps = self.steps;
        mirror.frames = self.frames;
        mirror.history.clone_from(&self.history);
        mirror.record.truncate(self.rows_from);
        mirror.record.append(&mut self.new_rows);
        mirror.peak_kinetic = self.peak_kinetic;
        mirror.fault.clone_from(&self.fault);
        if let Some(scene) = self.scene.take() {
            mirror.scene = scene;
        }
        if let Some(touched) = self.touched.take() {
            mirror.touched = touched;
        }
        mirror.held = self.held;
    }
}

/// The stepping side's part in publishing one simulation: the buffer the next snapshot's
/// positions are copied into, and how much of the record was published.
#[derive(Debug, Default)]
struct Publisher {
    spare: Vec<cloth_solver::Vec3>,
    /// The record's generation and length at the last snapshot.
    published: (u64, usize),
    /// The scene at the last snapshot.
    scene: Option<std::sync::Arc<cloth_scene::Scene>>,
    /// The generation and number of touches at the last snapshot.
    touched: (u64, usize),
}

impl Publisher {
    /// Copies `sim`'s positions into the spare buffer: done before taking the lock, so the UI
    /// never waits on a big cloth's copy.
    pub fn copy(&mut self, sim: &Run) {
        self.spare.clone_from(&sim.state.positions);
    }

    /// Fills `p` (under the lock) from `sim`, handing over the positions copied last.
    pub fn fill(&mut self, sim: &Run, p: &mut Cloth) {
        std::mem::swap(&mut p.positions, &mut self.spare);
        p.time = sim.time;
        p.steps = sim.steps;
        p.frames = sim.frames;
        p.history.clone_from(&sim.history);
        // NOTE: only the rows since the last snapshot travel, so a long run's table is
        // copied once, not at every draw; a reset starts the table again.
        if sim.generation != self.published.0 {
            self.published = (sim.generation, 0);
            p.new_rows.clear();
        }
        if p.new_rows.is_empty() {
            p.rows_from = self.published.1;
        }
        let from = self.published.1.min(sim.record.len());
        p.new_rows.extend_from_slice(&sim.record[from..]);
        self.published.1 = sim.record.len();
        p.peak_kinetic = sim.peak_kinetic;
        p.fault.clone_from(&sim.fault);
        p.held = sim.held;
        // NOTE: the scene and the touches travel only when they changed, and stay in the
        // snapshot until adopted (a snapshot not taken is filled again over them).
        if self
            .scene
            .as_ref()
            .is_none_or(|s| !std::sync::Arc::ptr_eq(s, &sim.scene))
        {
            self.scene = Some(std::sync::Arc::clone(&sim.scene));
            p.scene = Some(std::sync::Arc::clone(&sim.scene));
        }
        let touched = (sim.generation, sim.touched.len());
        if touched != self.touched {
            self.touched = touched;
            p.touched = Some(sim.touched.clone());
        }
    }
}

/// What a stepping thread published: `C`, the cloth (or the cloths), and the news.
#[derive(Debug, Default)]
struct Published<C> {
    cloth: C,
    /// Whether simulated time is advancing (a stop pauses it).
    running: bool,
    rates: Rates,
    /// Set by the thread when this is newer than what the UI last adopted.
    fresh: bool,
    /// Errors of commands, for the message line.
    errors: Vec<String>,
    /// Commands applied before this snapshot was taken.
    applied: u64,
}

/// Where a stepping thread leaves its snapshots of `C` (a [`Cloth`], or compare mode's one per
/// variant) and the UI takes them: the one exchange between the two, with the UI's wish for the
/// next snapshot, its count of commands sent and its leaving.
struct Mailbox<C> {
    published: Mutex<Published<C>>,
    /// The UI wants the next state (it has drawn the last one).
    wanted: AtomicBool,
    /// The UI is gone: end the thread.
    stop: AtomicBool,
    /// Commands sent so far: a snapshot taken before the thread applied them all is stale.
    sent: AtomicU64,
}

impl<C: Default> Mailbox<C> {
    /// An empty mailbox holding `cloth` to fill.
    pub fn new(cloth: C) -> Arc<Self> {
        Arc::new(Self {
            published: Mutex::new(Published {
                cloth,
                ..Published::default()
            }),
            wanted: AtomicBool::new(true),
            stop: AtomicBool::new(false),
            sent: AtomicU64::new(0),
        })
    }
}

impl<C> Mailbox<C> {
    fn lock(&self) -> std::sync::MutexGuard<'_, Published<C>> {
        self.published
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// The UI's side: counts a command sent.
    pub fn count_sent(&self) {
        self.sent.fetch_add(1, Ordering::AcqRel);
    }

    /// The UI's side: hands the newest snapshot to `adopt` and asks for the next; `None` when
    /// nothing new arrived.
    pub fn take(&self, adopt: impl FnOnce(&mut C)) -> Option<Adopted> {
        let mut p = self.lock();
        if !p.fresh {
            return None;
        }
        p.fresh = false;
        if p.applied < self.sent.load(Ordering::Acquire) {
            // Taken before the thread saw the latest commands (a reset, a pause): showing it
            // would undo them on screen for a moment. The next one follows.
            drop(p);
            self.wanted.store(true, Ordering::Release);
            return None;
        }
        adopt(&mut p.cloth);
        let adopted = Adopted {
            running: p.running,
            errors: std::mem::take(&mut p.errors),
            rates: p.rates,
        };
        drop(p);
        self.wanted.store(true, Ordering::Release);
        Some(adopted)
    }

    /// The UI's side: it is gone; the thread ends at its next look.
    pub fn leave(&self) {
        self.stop.store(true, Ordering::Release);
    }

    /// The thread's side: whether the UI is gone.
    pub fn left(&self) -> bool {
        self.stop.load(Ordering::Acquire)
    }

    /// The thread's side: whether the UI has drawn the last snapshot and wants the next.
    pub fn wanted(&self) -> bool {
        self.wanted.load(Ordering::Acquire)
    }

    /// The thread's side: publishes, `fill` writing the cloth under the lock (copy big
    /// buffers before, so the UI never waits on them), with the news.
    pub fn put(
        &self,
        running: bool,
        rates: Rates,
        errors: &mut Vec<String>,
        applied: u64,
        fill: impl FnOnce(&mut C),
    ) {
        self.wanted.store(false, Ordering::Release);
        let mut p = self.lock();
        fill(&mut p.cloth);
        p.running = running;
        p.rates = rates;
        p.errors.append(errors);
        p.applied = applied;
        p.fresh = true;
    }
}

/// Rates over a window of wall time.
struct Meter {
    /// When the window began.
    pub start: Instant,
    /// Solver steps taken in it.
    pub steps: u64,
    /// Simulated seconds advanced in it.
    pub sim_time: f64,
    /// Whether owed time was dropped in it.
    pub lagging: bool,
}

impl Meter {
    /// A window beginning `now`.
    pub fn new(now: Instant) -> Self {
        Self {
            start: now,
            steps: 0,
            sim_time: 0.0,
            lagging: false,
        }
    }

    /// The rates over the window once it has lasted [`WINDOW`] at `now` (`rate`: simulated
    /// seconds per wall second asked for), starting the next window; `None` before.
    pub fn rates(&mut self, now: Instant, rate: f64) -> Option<Rates> {
        let span = now.duration_since(self.start);
        if span < WINDOW {
            return None;
        }
        let s = span.as_secs_f64();
        let realtime_factor = self.sim_time / s / rate;
        let rates = Rates {
            realtime_factor,
            steps_per_sec: self.steps as f64 / s,
            // NOTE: owed time dropped in a window that still advanced at the rate asked for
            // (it paid a debt from before: a hitch, a solver being built) is no sign of a
            // cloth slower than real time, and "slower than real time: 1.03x" reads false.
            lagging: self.lagging && realtime_factor < 1.0,
            measured: true,
        };
        *self = Self::new(now);
        Some(rates)
    }
}

/// A command for every variant (`None`) or for one, by its index in the study.
type Order = (Option<usize>, Command);

/// Steps every variant of `sims` that has not stopped to the end of frame `target` (its
/// [`Run::frames`] reaching it), on up to `threads` threads, leaving a variant off between two
/// steps when `leave_off` (given the steps it took in this call) says so; true when every
/// variant that has not stopped has ended the frame.
///
/// A variant mid-frame (after leaving off) goes on from where it left off, so a frame finished
/// later has the bits of one never interrupted. A variant's fault stays in its run and ends its
/// part: it stops alone.
pub fn advance(
    sims: &mut [&mut Run],
    target: u64,
    threads: usize,
    leave_off: &(dyn Fn(u64) -> bool + Sync),
) -> bool {
    let behind = |s: &Run| s.fault.is_none() && s.frames < target;
    let finish = |sim: &mut Run| {
        let mut taken = 0;
        while behind(sim) && !leave_off(taken) {
            // NOTE: a failed step leaves the fault in the simulation (its last good frame put
            // back), which ends this loop: the variant stops alone.
            if sim.step().is_err() {
                break;
            }
            taken += 1;
        }
    };
    let threads = threads.min(sims.iter().filter(|s| behind(s)).count());
    if threads <= 1 {
        for sim in sims.iter_mut() {
            finish(sim);
        }
    } else {
        let next = AtomicUsize::new(0);
        let slots: Vec<Mutex<&mut Run>> = sims.iter_mut().map(|s| Mutex::new(&mut **s)).collect();
        let work = || {
            while let Some(slot) = slots.get(next.fetch_add(1, Ordering::AcqRel)) {
                finish(&mut slot.lock().unwrap_or_else(PoisonError::into_inner));
            }
        };
        std::thread::scope(|s| {
            for _ in 1..threads {
                s.spawn(work);
            }
            work();
        });
    }
    !sims.iter().any(|s| behind(s))
}

/// The frame the variants of `sims` are at: that of those that have not stopped (all at the
/// same one between frames), or the furthest any reached when all have stopped.
pub fn frame_of(sims: &[&Run]) -> (u64, f64) {
    let live = sims.iter().find(|s| s.fault.is_none());
    let s = live.or_else(|| sims.iter().max_by_key(|s| s.frames));
    s.map_or((0, 0.0), |s| (s.frames, s.time))
}

/// The variants of a study stepping in lockstep on a thread of their own.
pub struct Lockstep {
    commands: Sender<Order>,
    /// Each variant's cloth, in the study's order, and the news.
    mailbox: Arc<Mailbox<Vec<Cloth>>>,
    /// A command is waiting: the frame in progress leaves off between two steps.
    interrupt: Arc<AtomicBool>,
}

impl Lockstep {
    /// Starts the variants `sims` (all at the same frame) on a new thread, running or paused
    /// at `rate`, stepping each frame on up to `threads` threads; `notify` is called (on the
    /// coordinator's thread) whenever a snapshot is ready.
    ///
    /// # Errors
    /// When the thread cannot be started.
    pub fn spawn(
        sims: Vec<Run>,
        running: bool,
        rate: f64,
        threads: usize,
        notify: Box<dyn Fn() + Send>,
    ) -> std::io::Result<Self> {
        if sims.is_empty() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "a lockstep needs at least one run to step",
            ));
        }
        let (tx, rx) = mpsc::channel();
        let mailbox = Mailbox::new(sims.iter().map(|_| Cloth::default()).collect());
        let interrupt = Arc::new(AtomicBool::new(false));
        let (inner, flag) = (Arc::clone(&mailbox), Arc::clone(&interrupt));
        let frame = frame_of(&sims.iter().collect::<Vec<_>>()).0;
        std::thread::Builder::new()
            .name("clothsim-lockstep".to_owned())
            .spawn(move || {
                Coordinator {
                    publishers: sims.iter().map(|_| Publisher::default()).collect(),
                    sims,
                    frame,
                    running,
                    rate,
                    threads: threads.max(1),
                    commands: rx,
                    mailbox: inner,
                    interrupt: flag,
                    notify,
                }
                .run();
            })?;
        Ok(Self {
            commands: tx,
            mailbox,
            interrupt,
        })
    }

    /// Sends `command` to every variant (taken between two steps).
    pub fn send(&self, command: Command) {
        self.order((None, command));
    }

    /// Sends `command` to the variant at `index` in the study's order.
    pub fn send_to(&self, index: usize, command: Command) {
        self.order((Some(index), command));
    }

    fn order(&self, order: Order) {
        // NOTE: a send fails only when the thread has ended (a simulation panicked); the UI
        // then sees no more snapshots and says so rather than stopping here.
        if self.commands.send(order).is_ok() {
            self.mailbox.count_sent();
            self.interrupt.store(true, Ordering::Release);
        }
    }

    /// Whether the thread is still there to step.
    pub fn alive(&self) -> bool {
        Arc::strong_count(&self.mailbox) > 1
    }

    /// Moves the newest snapshot into `mirrors` (the UI's copies, in the study's order) and
    /// asks for the next; `None` when nothing new arrived.
    pub fn adopt_into(&self, mirrors: &mut [&mut Run]) -> Option<Adopted> {
        self.mailbox.take(|cloths| {
            for (cloth, mirror) in cloths.iter_mut().zip(mirrors.iter_mut()) {
                cloth.adopt_into(mirror);
            }
        })
    }
}

impl Drop for Lockstep {
    fn drop(&mut self) {
        // The thread ends between two steps; it is not joined, so quitting never waits for a
        // long step of a big cloth.
        self.mailbox.leave();
        self.interrupt.store(true, Ordering::Release);
    }
}

/// The thread's side.
struct Coordinator {
    sims: Vec<Run>,
    publishers: Vec<Publisher>,
    /// The group's frame: every variant that has not stopped has ended it.
    frame: u64,
    running: bool,
    rate: f64,
    threads: usize,
    commands: Receiver<Order>,
    mailbox: Arc<Mailbox<Vec<Cloth>>>,
    interrupt: Arc<AtomicBool>,
    notify: Box<dyn Fn() + Send>,
}

impl Coordinator {
    fn run(mut self) {
        let mut errors = Vec::new();
        let mut held: Option<Order> = None;
        let mut debt = 0.0_f64;
        let mut last = Instant::now();
        let mut meter = Meter::new(last);
        let mut rates = Rates::default();
        let mut force = true;
        let mut applied = 0_u64;
        // A frame begun and not yet ended by every variant.
        let mut in_frame = false;
        // Whether the clock began it (not a single frame asked for, which ends even paused).
        let mut clock_frame = false;
        // Single frames asked for and not yet begun.
        let mut asked = 0_u64;
        loop {
            if self.mailbox.left() {
                return;
            }
            let mut pending: Vec<Order> = held.take().into_iter().collect();
            if pending.is_empty() && !self.running && !in_frame && asked == 0 && !force {
                // Paused: nothing to do but wait for a command.
                match self.commands.recv_timeout(IDLE) {
                    Ok(c) => pending.push(c),
                    Err(RecvTimeoutError::Timeout) => continue,
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            }
            // NOTE: cleared before the queue is read, so a command sent after the read sets it
            // again and the next frame leaves off for it.
            self.interrupt.store(false, Ordering::Release);
            pending.extend(self.commands.try_iter());
            let applying = Instant::now();
            let any = !pending.is_empty();
            for (target, c) in pending {
                force = true;
                applied += 1;
                match c {
                    Command::Run { running, rate } => {
                        self.running = running && self.any_live();
                        self.rate = rate;
                        debt = 0.0;
                        last = Instant::now();
                        meter = Meter::new(last);
                        rates = Rates::default();
                    }
                    Command::StepFrame => {
                        self.running = false;
                        debt = 0.0;
                        if self.any_live() {
                            asked += 1;
                        } else {
                            errors.push(self.stopped_message());
                        }
                    }
                    Command::Reset => {
                        for sim in &mut self.sims {
                            sim.reset();
                        }
                        self.frame = 0;
                        in_frame = false;
                        asked = 0;
                        debt = 0.0;
                    }
                    Command::ResumeAnyway if self.sims.len() == 1 => {
                        // A single cloth has no group to keep up with: it goes on from its
                        // last good frame.
                        if let Err(e) = self.sims[0].resume_anyway() {
                            errors.push(e);
                        }
                        self.frame = self.sims[0].frames;
                        in_frame = false;
                    }
                    Command::ResumeAnyway => errors.push(
                        "a stopped variant stays stopped, so the variants stay at one frame: \
                         r resets all"
                            .to_owned(),
                    ),
                    other => {
                        for (i, sim) in self.sims.iter_mut().enumerate() {
                            if target.is_none_or(|t| t == i)
                                && let Err(e) = sim.apply(other.clone())
                            {
                                errors.push(e);
                            }
                        }
                    }
                }
            }
            if any {
                // NOTE: the time spent applying commands (a new solver built, a big cloth's
                // factorisation) is not owed: the cloth waits for the change as it waits for
                // a pause, rather than rushing afterwards to catch up.
                last = (last + applying.elapsed()).min(Instant::now());
            }

            if self.running {
                self.owe(&mut debt, &mut last, &mut meter);
                if !in_frame {
                    let span = self.frame_span();
                    if debt >= span {
                        debt -= span;
                        in_frame = true;
                        clock_frame = true;
                    } else {
                        // Ahead of the clock: sleep until the next frame is owed, or a command.
                        let wait = Duration::from_secs_f64(((span - debt) / self.rate).min(0.05));
                        match self.commands.recv_timeout(wait) {
                            Ok(c) => held = Some(c),
                            Err(RecvTimeoutError::Timeout) => {}
                            Err(RecvTimeoutError::Disconnected) => return,
                        }
                    }
                }
            }
            let single = self.sims.len() == 1;
            if single && !self.running && clock_frame {
                // A single cloth pauses between any two steps: it has no group to stay at one
                // frame with, and a frame of a big cloth can take seconds.
                in_frame = false;
                clock_frame = false;
            }
            if !in_frame && asked > 0 {
                asked -= 1;
                in_frame = true;
                clock_frame = false;
            }
            if in_frame {
                let before = self.steps();
                let stopped = self.sims.iter().filter(|s| s.fault.is_some()).count();
                let lead = self.lead();
                let lead_time = self.sims[lead].time;
                let (interrupt, mailbox) = (&self.interrupt, &self.mailbox);
                // NOTE: a single cloth also leaves off, after a step, when the UI wants a
                // snapshot: several are shown only at one frame, but one is always consistent.
                let leave_off = |taken: u64| {
                    interrupt.load(Ordering::Acquire) || single && taken > 0 && mailbox.wanted()
                };
                let mut sims: Vec<&mut Run> = self.sims.iter_mut().collect();
                let ended = advance(&mut sims, self.frame + 1, self.threads, &leave_off);
                meter.steps += self.steps().saturating_sub(before);
                meter.sim_time += (self.sims[lead].time - lead_time).max(0.0);
                if ended {
                    in_frame = false;
                    self.frame += 1;
                    // A single frame, or the last before a pause: shown at once.
                    force |= !self.running;
                }
                if self.sims.iter().filter(|s| s.fault.is_some()).count() != stopped {
                    // A variant stopped: say so at once; when none is left, the group stops.
                    force = true;
                    if !self.any_live() {
                        self.running = false;
                        in_frame = false;
                    }
                }
            }
            if self.running {
                // Owed again before the window closes, so a frame too long to keep real time
                // counts as lagging in the window it ends.
                self.owe(&mut debt, &mut last, &mut meter);
                if let Some(r) = meter.rates(Instant::now(), self.rate) {
                    rates = r;
                }
            }

            // NOTE: several variants only between frames, so every variant shown is at the same
            // frame.
            if (!in_frame || single) && (force || self.running && self.mailbox.wanted()) {
                self.publish(&mut errors, rates, applied);
                force = false;
            }
        }
    }

    /// Adds the wall time since `last` to the simulated time owed; what exceeds
    /// [`MAX_DEBT`] is forgiven and the window marked lagging.
    fn owe(&self, debt: &mut f64, last: &mut Instant, meter: &mut Meter) {
        let now = Instant::now();
        *debt += now.duration_since(*last).as_secs_f64() * self.rate;
        *last = now;
        let cap = MAX_DEBT.as_secs_f64() * self.rate;
        if *debt > cap {
            *debt = cap;
            meter.lagging = true;
        }
    }

    fn any_live(&self) -> bool {
        self.sims.iter().any(|s| s.fault.is_none())
    }

    /// The first variant that has not stopped (the first when all have): the one whose clock
    /// the group's follows.
    fn lead(&self) -> usize {
        self.sims
            .iter()
            .position(|s| s.fault.is_none())
            .unwrap_or(0)
    }

    /// What a single frame asked of a group with no variant left to step says.
    fn stopped_message(&self) -> String {
        match &self.sims[..] {
            [one] => one.fault.as_ref().map_or_else(String::new, |f| {
                format!("{}; it cannot go on: press r to reset", f.what)
            }),
            _ => "every variant has stopped: r resets all".to_owned(),
        }
    }

    /// Simulated seconds of one frame: the first variant's that has not stopped.
    fn frame_span(&self) -> f64 {
        1.0 / self.sims[self.lead()].settings.params.frames_per_sec
    }

    /// Steps taken by all the variants together.
    fn steps(&self) -> u64 {
        self.sims.iter().map(|s| s.steps).sum()
    }

    fn publish(&mut self, errors: &mut Vec<String>, rates: Rates, applied: u64) {
        for (publisher, sim) in self.publishers.iter_mut().zip(&self.sims) {
            publisher.copy(sim);
        }
        let (publishers, sims) = (&mut self.publishers, &self.sims);
        self.mailbox
            .put(self.running, rates, errors, applied, |cloths| {
                for ((publisher, sim), cloth) in publishers.iter_mut().zip(sims).zip(cloths) {
                    publisher.fill(sim, cloth);
                }
            });
        (self.notify)();
    }
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc;
    use std::time::Duration;

    use super::*;

    /// `pinned4` with `set`, as a UI variant is built.
    fn variant(set: &str) -> Run {
        let scene = cloth_scene::load("pinned4", &[set.to_owned()]).unwrap();
        Run::new(scene, crate::default_registry(), None).unwrap()
    }

    /// The positions after `frames` frames of `pinned4 --set set`, stepped as `simulate` steps
    /// (one run of its own, without the UI's accumulator or coordinator).
    fn separate_run(set: &str, frames: u64) -> Vec<cloth_solver::Vec3> {
        let mut run = variant(set);
        run.set_recording(false);
        for _ in 1..=frames {
            run.step_frame().unwrap();
        }
        run.state.positions
    }

    const SETS: [&str; 3] = ["cloth.ks=1", "cloth.ks=5000", "cloth.ks=100000"];

    /// A coordinator on the variants of `sets`, its snapshots counted on the returned channel,
    /// and the UI's copies.
    fn group(sets: &[&str], running: bool) -> (Lockstep, mpsc::Receiver<()>, Vec<Run>) {
        let (tx, rx) = mpsc::channel();
        let tx = Mutex::new(tx);
        let sims = sets.iter().map(|s| variant(s)).collect();
        let g = Lockstep::spawn(
            sims,
            running,
            1.0,
            2,
            Box::new(move || {
                let _ = tx.lock().unwrap().send(());
            }),
        )
        .unwrap();
        (g, rx, sets.iter().map(|s| variant(s)).collect())
    }

    /// Adopts snapshots until `done` holds of the copies; the last snapshot's news.
    fn until(
        g: &Lockstep,
        rx: &mpsc::Receiver<()>,
        mirrors: &mut [Run],
        done: impl Fn(&[Run], &Adopted) -> bool,
    ) -> Adopted {
        loop {
            rx.recv_timeout(Duration::from_secs(120))
                .expect("a snapshot within two minutes");
            let mut refs: Vec<&mut Run> = mirrors.iter_mut().collect();
            if let Some(a) = g.adopt_into(&mut refs)
                && done(mirrors, &a)
            {
                return a;
            }
        }
    }

    /// Every copy is at frame `frames` with the bits of its separate run.
    fn each_equals_its_separate_run(mirrors: &[Run], frames: u64) {
        each_equals_its_run(mirrors, &SETS, frames);
    }

    /// Every copy (of `sets`) is at frame `frames` with the bits of its separate run.
    fn each_equals_its_run(mirrors: &[Run], sets: &[&str], frames: u64) {
        for (sim, &set) in mirrors.iter().zip(sets) {
            assert_eq!(
                sim.frames, frames,
                "{set}: every variant at the group's frame"
            );
            assert_eq!(
                sim.steps,
                frames * u64::from(sim.settings.params.steps_per_frame),
                "{set}: whole frames only"
            );
            assert!(
                sim.state.positions == separate_run(set, frames),
                "{set}: the bits of `simulate --set {set} --frames {frames}`"
            );
        }
    }

    #[test]
    fn a_window_is_lagging_only_when_it_dropped_time_and_ran_below_the_rate() {
        let t0 = Instant::now();
        let window = |sim_time: f64, dropped: bool| {
            let mut m = Meter::new(t0);
            m.sim_time = sim_time;
            m.steps = 2700;
            m.lagging = dropped;
            m.rates(t0 + WINDOW, 1.0).expect("a whole window")
        };
        // A debt paid after a hitch: more than a second simulated in the second, though time
        // was dropped in it.
        let paid = window(1.03, true);
        assert!(!paid.lagging && (paid.realtime_factor - 1.03).abs() < 1e-12);
        // Too slow to keep up: time dropped and less simulated than the wall time.
        let slow = window(0.6, true);
        assert!(slow.lagging, "{slow:?}");
        assert!(
            !window(0.6, false).lagging,
            "nothing dropped: behind by design (a rate)"
        );
    }

    #[test]
    fn single_frames_step_every_variant_once_with_the_bits_of_separate_runs() {
        let (g, rx, mut mirrors) = group(&SETS, false);
        for _ in 0..3 {
            g.send(Command::StepFrame);
        }
        let got = until(&g, &rx, &mut mirrors, |m, _| {
            m.iter().all(|s| s.frames == 3)
        });
        assert!(!got.running);
        each_equals_its_separate_run(&mirrors, 3);
    }

    #[test]
    fn running_then_pausing_leaves_every_variant_at_one_frame_and_a_reset_starts_all_again() {
        let (g, rx, mut mirrors) = group(&SETS, false);
        // Sixteen times real time: more than two cores pay, so the group lags as one.
        g.send(Command::Run {
            running: true,
            rate: 16.0,
        });
        until(&g, &rx, &mut mirrors, |m, _| m[0].frames >= 10);
        g.send(Command::Run {
            running: false,
            rate: 16.0,
        });
        let got = until(&g, &rx, &mut mirrors, |_, a| !a.running);
        let frames = mirrors[0].frames;
        assert!(!got.running && frames >= 10);
        // Paused: no frame is left half done, every variant ended the same one.
        each_equals_its_separate_run(&mirrors, frames);

        g.send(Command::Reset);
        g.send(Command::StepFrame);
        g.send(Command::StepFrame);
        until(&g, &rx, &mut mirrors, |m, _| {
            m.iter().all(|s| s.frames == 2 && s.record.len() == 3)
        });
        each_equals_its_separate_run(&mirrors, 2);
    }

    #[test]
    fn variants_of_different_solvers_and_steps_per_frame_end_each_frame_together() {
        let sets = ["simulation.solver=verlet", "simulation.solver=implicit"];
        let (g, rx, mut mirrors) = group(&sets, false);
        assert_ne!(
            mirrors[0].settings.params.steps_per_frame, mirrors[1].settings.params.steps_per_frame,
            "each solver its own steps per frame"
        );
        for _ in 0..2 {
            g.send(Command::StepFrame);
        }
        until(&g, &rx, &mut mirrors, |m, _| {
            m.iter().all(|s| s.frames == 2)
        });
        each_equals_its_run(&mirrors, &sets, 2);
    }

    #[test]
    fn a_diverging_variant_stops_alone_and_the_others_go_on() {
        // Density 0.1 g/cm^2 at ks = 5000 N/m is past Verlet's stability limit; 15 is the
        // course's and holds.
        let sets = ["cloth.density=0.1", "cloth.density=15"];
        let (g, rx, mut mirrors) = group(&sets, true);
        g.send(Command::Run {
            running: true,
            rate: 16.0,
        });
        let got = until(&g, &rx, &mut mirrors, |m, _| {
            m[0].fault.is_some() && m[1].frames >= m[0].frames + 30
        });
        assert!(got.running, "the group goes on");
        assert!(mirrors[1].fault.is_none(), "the steady variant goes on");
        let stopped = mirrors[0].frames;
        until(&g, &rx, &mut mirrors, |m, _| m[1].frames > stopped + 40);
        assert_eq!(
            mirrors[0].frames, stopped,
            "the stopped one stays where it stopped"
        );
        // An edit of the stopped one is taken and does not restart it.
        g.send_to(0, Command::Settings(mirrors[0].settings.clone()));
        g.send(Command::ResumeAnyway);
        let got = until(&g, &rx, &mut mirrors, |_, a| !a.errors.is_empty());
        assert!(got.errors[0].contains("r resets all"), "{:?}", got.errors);
        assert!(mirrors[0].fault.is_some());
    }

    #[test]
    fn an_interrupted_frame_finishes_with_the_bits_of_one_never_interrupted() {
        let mut sims: Vec<Run> = SETS.iter().map(|s| variant(s)).collect();
        let mut refs: Vec<&mut Run> = sims.iter_mut().collect();
        let interrupt = AtomicBool::new(true);
        let leave_off = |_| interrupt.load(Ordering::Acquire);
        assert!(
            !advance(&mut refs, 1, 2, &leave_off),
            "a waiting command comes first"
        );
        assert!(refs.iter().all(|s| s.steps == 0), "no step taken");
        // One variant left mid-frame (as an interruption leaves it) goes on from there.
        for _ in 0..7 {
            refs[1].step().unwrap();
        }
        interrupt.store(false, Ordering::Release);
        assert!(advance(&mut refs, 1, 2, &leave_off));
        assert!(
            advance(&mut refs, 2, 1, &leave_off),
            "one thread or two, the same"
        );
        each_equals_its_separate_run(&sims, 2);
    }

    #[test]
    fn a_single_cloth_steps_a_frame_with_the_bits_of_a_separate_run() {
        let (g, rx, mut mirrors) = group(&SETS[1..2], false);
        g.send(Command::StepFrame);
        let got = until(&g, &rx, &mut mirrors, |m, _| m[0].frames == 1);
        assert!(!got.running);
        each_equals_its_run(&mirrors, &SETS[1..2], 1);
    }

    #[test]
    fn a_running_single_cloth_advances_and_a_reset_takes_it_back() {
        let (g, rx, mut mirrors) = group(&SETS[1..2], true);
        until(&g, &rx, &mut mirrors, |m, _| m[0].frames >= 3);
        g.send(Command::Run {
            running: false,
            rate: 1.0,
        });
        g.send(Command::Reset);
        let got = until(&g, &rx, &mut mirrors, |_, _| true);
        assert!(!got.running);
        assert_eq!(mirrors[0].time, 0.0);
        assert_eq!(
            mirrors[0].state.positions,
            mirrors[0].scene.mesh.start_positions(),
            "a snapshot older than the reset is never shown"
        );
    }

    #[test]
    fn the_mirror_gets_every_frame_s_row_once_and_a_reset_starts_the_table_again() {
        let (g, rx, mut mirrors) = group(&SETS[1..2], false);
        for _ in 0..3 {
            g.send(Command::StepFrame);
        }
        until(&g, &rx, &mut mirrors, |m, _| m[0].frames == 3);
        let frames: Vec<u64> = mirrors[0].record.iter().map(|r| r.frame).collect();
        assert_eq!(frames, [0, 1, 2, 3], "each frame once, in order");
        g.send(Command::Reset);
        mirrors[0].reset();
        g.send(Command::StepFrame);
        until(&g, &rx, &mut mirrors, |m, _| m[0].frames == 1);
        let frames: Vec<u64> = mirrors[0].record.iter().map(|r| r.frame).collect();
        assert_eq!(frames, [0, 1]);
    }

    #[test]
    fn a_single_cloth_is_shown_and_paused_between_steps_and_its_frame_ends_with_the_same_bits() {
        // A frame of 3,000 steps: long enough to be seen mid-way, as a big cloth's frame is.
        let set = ["simulation.simulation_steps=3000"];
        let (g, rx, mut mirrors) = group(&set, false);
        g.send(Command::Run {
            running: true,
            rate: 1.0,
        });
        until(&g, &rx, &mut mirrors, |m, _| m[0].steps > 0);
        assert_eq!(mirrors[0].frames, 0, "shown before its first frame ends");
        g.send(Command::Run {
            running: false,
            rate: 1.0,
        });
        until(&g, &rx, &mut mirrors, |_, a| !a.running);
        let paused_at = mirrors[0].steps;
        assert!(
            paused_at % 3000 != 0,
            "a pause takes effect between two steps, not at the frame's end ({paused_at})"
        );
        g.send(Command::StepFrame);
        until(&g, &rx, &mut mirrors, |m, _| m[0].frames == 1);
        each_equals_its_run(&mirrors, &set, 1);
    }

    /// Processor time of this process so far, s (Linux: `/proc/self/stat`, in ticks of 1/100 s).
    fn cpu_seconds() -> Option<f64> {
        let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
        let after = stat.rsplit_once(')')?.1;
        let fields: Vec<&str> = after.split_whitespace().collect();
        let ticks: f64 =
            fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
        Some(ticks / 100.0)
    }

    /// Four `pinned4` variants for 3 s simulated (270 frames) through the live UI's coordinator:
    /// at real time (is it kept?) and at sixteen times (how fast can the group go?). Prints the
    /// wall and processor time and the real-time factor; asserts only the lockstep.
    #[test]
    #[ignore = "a measurement: run in release with --nocapture"]
    fn four_pinned4_variants_for_three_simulated_seconds() {
        let sets = [
            "cloth.ks=1",
            "cloth.ks=5000",
            "cloth.ks=20000",
            "cloth.ks=100000",
        ];
        for rate in [1.0, 16.0] {
            let (g, rx, mut mirrors) = group(&sets, false);
            let cpu = cpu_seconds();
            let start = Instant::now();
            g.send(Command::Run {
                running: true,
                rate,
            });
            // The rates of the last measured window, and whether any window lagged.
            let seen = std::cell::Cell::new((0.0, false));
            until(&g, &rx, &mut mirrors, |m, a| {
                if a.rates.measured {
                    let lagged = seen.get().1 || a.rates.lagging;
                    seen.set((a.rates.realtime_factor, lagged));
                }
                m[0].frames >= 270
            });
            let wall = start.elapsed().as_secs_f64();
            let cpu = cpu.zip(cpu_seconds()).map(|(a, b)| b - a);
            g.send(Command::Run {
                running: false,
                rate,
            });
            until(&g, &rx, &mut mirrors, |_, a| !a.running);
            let frames = mirrors[0].frames;
            assert!(mirrors.iter().all(|s| s.frames == frames), "lockstep");
            let (factor, lagged) = seen.get();
            println!(
                "rate {rate}x: 270 frames (3 s simulated) in {wall:.2} s wall, {} processor; \
                 {:.2} x real time overall, the status line's last factor {factor:.2}, \
                 lagging {lagged}",
                cpu.map_or("unknown".to_owned(), |c| format!("{c:.2} s")),
                3.0 / wall,
            );
        }
    }
}
