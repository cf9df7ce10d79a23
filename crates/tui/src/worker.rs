//! A simulation on its own thread: the UI sends [`Command`]s and reads snapshots of it, so the
//! keyboard is answered at once however long a step takes.
//!
//! A worker owns one [`Run`] and its clock: while running it owes `wall * rate`
//! simulated seconds and pays them in fixed steps of `dt` (an accumulator); what it cannot pay
//! within [`MAX_DEBT`] of wall time it forgives and reports as lagging, so a slow cloth runs
//! below real time instead of falling ever further behind. Between any two steps it reads its
//! commands, so a pause, an edit or a reset waits for one step at most.
//!
//! The UI asks for a snapshot when it is ready to draw ([`Worker::adopt_into`]); the worker
//! publishes one after the next step (and at once after a stop or a single frame), swapping
//! position buffers rather than allocating, so a big cloth costs one copy per drawn frame.
//! Nothing here knows of the terminal. The exchange of snapshots ([`Mailbox`]), the snapshot of
//! one cloth ([`Cloth`], filled by a [`Publisher`]) and the rate [`Meter`] serve compare mode's
//! lockstep coordinator too ([`super::lockstep`]).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use cloth_run::{Command, Run};

/// Most wall time of owed simulation kept; beyond it the debt is forgiven (lagging).
///
/// NOTE: a quarter second keeps a brief hiccup (a slow draw, a busy machine) from losing
/// simulated time, yet a cloth that cannot keep up falls at most this far behind.
pub const MAX_DEBT: Duration = Duration::from_millis(250);

/// How often the rates are measured.
pub const WINDOW: Duration = Duration::from_secs(1);

/// Longest a paused worker sleeps before looking at its stop flag again.
pub const IDLE: Duration = Duration::from_millis(500);

/// How fast a worker runs, measured over about a second of wall time.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Rates {
    /// Simulated seconds per wall second, over the rate asked for (1 = keeping up).
    pub realtime_factor: f64,
    /// Solver steps per wall second.
    pub steps_per_sec: f64,
    /// Whether owed time was dropped because the steps could not keep up.
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
pub struct Cloth {
    /// Positions at the end of the last step taken.
    positions: Vec<cloth_solver::Vec3>,
    time: f64,
    steps: u64,
    frames: u64,
    history: std::collections::VecDeque<cloth_run::Sample>,
    /// Rows of the stepping side's record not yet adopted, which start at this index of it.
    rows_from: usize,
    new_rows: Vec<cloth_run::export::StatsRow>,
    peak_kinetic: f64,
    fault: Option<cloth_run::Fault>,
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
    }
}

/// The stepping side's part in publishing one simulation: the buffer the next snapshot's
/// positions are copied into, and how much of the record was published.
#[derive(Debug, Default)]
pub struct Publisher {
    spare: Vec<cloth_solver::Vec3>,
    /// The record's generation and length at the last snapshot.
    published: (u64, usize),
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
pub struct Mailbox<C> {
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

/// A simulation stepping on its own thread.
pub struct Worker {
    commands: Sender<Command>,
    mailbox: Arc<Mailbox<Cloth>>,
}

impl Worker {
    /// Starts `sim` on a new thread, running or paused at `rate`; `notify` is called (on the
    /// worker's thread) whenever a snapshot is ready.
    ///
    /// # Errors
    /// When the thread cannot be started.
    pub fn spawn(
        sim: Run,
        running: bool,
        rate: f64,
        notify: Box<dyn Fn() + Send>,
    ) -> std::io::Result<Self> {
        let (tx, rx) = mpsc::channel();
        let mailbox = Mailbox::new(Cloth::default());
        let inner = Arc::clone(&mailbox);
        std::thread::Builder::new()
            .name("clothsim-sim".to_owned())
            .spawn(move || {
                Stepper {
                    sim,
                    running,
                    rate,
                    commands: rx,
                    mailbox: inner,
                    notify,
                    publisher: Publisher::default(),
                }
                .run();
            })?;
        Ok(Self {
            commands: tx,
            mailbox,
        })
    }

    /// Sends a command (taken before the next step).
    pub fn send(&self, command: Command) {
        // NOTE: a send fails only when the thread has ended (its simulation panicked); the
        // UI then sees no more snapshots and says so rather than stopping here.
        if self.commands.send(command).is_ok() {
            self.mailbox.count_sent();
        }
    }

    /// Whether the thread is still there to step.
    pub fn alive(&self) -> bool {
        Arc::strong_count(&self.mailbox) > 1
    }

    /// Moves the newest snapshot into `mirror` (the UI's copy, whose settings, scene and
    /// solver the UI owns) and asks for the next; `None` when nothing new arrived.
    pub fn adopt_into(&self, mirror: &mut Run) -> Option<Adopted> {
        self.mailbox.take(|cloth| cloth.adopt_into(mirror))
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        // The thread ends after its current step; it is not joined, so quitting never waits
        // for a long step of a big cloth.
        self.mailbox.leave();
    }
}

/// The thread's side.
struct Stepper {
    sim: Run,
    running: bool,
    rate: f64,
    commands: Receiver<Command>,
    mailbox: Arc<Mailbox<Cloth>>,
    notify: Box<dyn Fn() + Send>,
    publisher: Publisher,
}

/// Rates over a window of wall time.
pub struct Meter {
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
        let rates = Rates {
            realtime_factor: self.sim_time / s / rate,
            steps_per_sec: self.steps as f64 / s,
            lagging: self.lagging,
            measured: true,
        };
        *self = Self::new(now);
        Some(rates)
    }
}

impl Stepper {
    fn run(mut self) {
        let mut errors = Vec::new();
        let mut held: Option<Command> = None;
        let mut debt = 0.0_f64;
        let mut last = Instant::now();
        let mut meter = Meter::new(last);
        let mut rates = Rates::default();
        let mut force = true;
        let mut applied = 0_u64;
        loop {
            if self.mailbox.left() {
                return;
            }
            let mut pending: Vec<Command> = held.take().into_iter().collect();
            if pending.is_empty() && !self.running && !force {
                // Paused: nothing to do but wait for a command.
                match self.commands.recv_timeout(IDLE) {
                    Ok(c) => pending.push(c),
                    Err(RecvTimeoutError::Timeout) => continue,
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            }
            pending.extend(self.commands.try_iter());
            for c in pending {
                force = true;
                applied += 1;
                match c {
                    Command::Run { running, rate } => {
                        self.running = running && self.sim.fault.is_none();
                        self.rate = rate;
                        debt = 0.0;
                        last = Instant::now();
                        meter = Meter::new(last);
                        rates = Rates::default();
                    }
                    other => {
                        if matches!(other, Command::StepFrame) {
                            self.running = false;
                        }
                        if matches!(other, Command::Reset | Command::StepFrame) {
                            debt = 0.0;
                        }
                        if let Err(e) = self.sim.apply(other) {
                            errors.push(e);
                        }
                    }
                }
            }

            if self.running {
                let now = Instant::now();
                let wall = now.duration_since(last);
                last = now;
                debt += wall.as_secs_f64() * self.rate;
                let cap = MAX_DEBT.as_secs_f64() * self.rate;
                if debt > cap {
                    debt = cap;
                    meter.lagging = true;
                }
                let dt = self.sim.dt();
                if debt >= dt {
                    debt -= dt;
                    let before = self.sim.time;
                    if self.sim.step().is_err() {
                        self.running = false;
                        force = true;
                    }
                    meter.steps += 1;
                    meter.sim_time += (self.sim.time - before).max(0.0);
                } else {
                    // Ahead of the clock: sleep until the next step is owed, or a command.
                    let wait = Duration::from_secs_f64(((dt - debt) / self.rate).min(0.05));
                    match self.commands.recv_timeout(wait) {
                        Ok(c) => held = Some(c),
                        Err(RecvTimeoutError::Timeout) => {}
                        Err(RecvTimeoutError::Disconnected) => return,
                    }
                }
                if let Some(r) = meter.rates(Instant::now(), self.rate) {
                    rates = r;
                }
            }

            if force || self.running && self.mailbox.wanted() {
                self.publish(&mut errors, rates, applied);
                force = false;
            }
        }
    }

    fn publish(&mut self, errors: &mut Vec<String>, rates: Rates, applied: u64) {
        self.publisher.copy(&self.sim);
        let (publisher, sim) = (&mut self.publisher, &self.sim);
        self.mailbox
            .put(self.running, rates, errors, applied, |cloth| {
                publisher.fill(sim, cloth);
            });
        (self.notify)();
    }
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc;
    use std::time::Duration;

    use cloth_mesh::ClothState;
    use cloth_solver::advance_frame;

    use super::*;

    fn pinned4() -> Run {
        let scene = cloth_scene::load("pinned4", &[]).unwrap();
        Run::new(scene, cloth_run::default_registry(), None).unwrap()
    }

    /// Waits for the worker's next current snapshot.
    fn next(w: &Worker, rx: &mpsc::Receiver<()>, mirror: &mut Run) -> Adopted {
        loop {
            rx.recv_timeout(Duration::from_secs(60))
                .expect("a snapshot within a minute");
            if let Some(a) = w.adopt_into(mirror) {
                return a;
            }
        }
    }

    #[test]
    fn a_frame_stepped_on_the_worker_has_the_bits_of_the_headless_path() {
        let (tx, rx) = mpsc::channel();
        let tx = Mutex::new(tx);
        let w = Worker::spawn(
            pinned4(),
            false,
            1.0,
            Box::new(move || {
                let _ = tx.lock().unwrap().send(());
            }),
        )
        .unwrap();
        let mut mirror = pinned4();
        w.send(Command::StepFrame);
        let mut got = next(&w, &rx, &mut mirror);
        while mirror.frames < 1 {
            got = next(&w, &rx, &mut mirror);
        }
        assert!(!got.running);
        assert_eq!(mirror.steps, 30);
        let scene = cloth_scene::load("pinned4", &[]).unwrap();
        let mut state = ClothState::new(&scene.mesh);
        // The headless path builds the same solver the same way: through the registry.
        let mut solver = cloth_run::solvers::choose(&cloth_run::default_registry(), &scene, None)
            .unwrap()
            .build(&scene.mesh)
            .unwrap();
        advance_frame(
            solver.as_mut(),
            &scene.mesh,
            &scene.colliders,
            &scene.params,
            &mut state,
        )
        .unwrap();
        assert_eq!(
            mirror.state.positions, state.positions,
            "same steps, same bits"
        );
    }

    #[test]
    fn a_running_worker_advances_and_a_reset_takes_it_back() {
        let (tx, rx) = mpsc::channel();
        let tx = Mutex::new(tx);
        let w = Worker::spawn(
            pinned4(),
            true,
            1.0,
            Box::new(move || {
                let _ = tx.lock().unwrap().send(());
            }),
        )
        .unwrap();
        let mut mirror = pinned4();
        while mirror.frames < 3 {
            next(&w, &rx, &mut mirror);
        }
        w.send(Command::Run {
            running: false,
            rate: 1.0,
        });
        w.send(Command::Reset);
        let got = next(&w, &rx, &mut mirror);
        assert!(!got.running);
        assert_eq!(mirror.time, 0.0);
        assert_eq!(
            mirror.state.positions,
            mirror.scene.mesh.start_positions(),
            "a snapshot older than the reset is never shown"
        );
    }

    #[test]
    fn the_mirror_gets_every_frame_s_row_once_and_a_reset_starts_the_table_again() {
        let (tx, rx) = mpsc::channel();
        let tx = Mutex::new(tx);
        let w = Worker::spawn(
            pinned4(),
            false,
            1.0,
            Box::new(move || {
                let _ = tx.lock().unwrap().send(());
            }),
        )
        .unwrap();
        let mut mirror = pinned4();
        for _ in 0..3 {
            w.send(Command::StepFrame);
        }
        while mirror.frames < 3 {
            next(&w, &rx, &mut mirror);
        }
        let frames: Vec<u64> = mirror.record.iter().map(|r| r.frame).collect();
        assert_eq!(frames, [0, 1, 2, 3], "each frame once, in order");
        w.send(Command::Reset);
        mirror.reset();
        w.send(Command::StepFrame);
        while mirror.frames < 1 {
            next(&w, &rx, &mut mirror);
        }
        let frames: Vec<u64> = mirror.record.iter().map(|r| r.frame).collect();
        assert_eq!(frames, [0, 1]);
    }
}
