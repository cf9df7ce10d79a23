//! The app loop: the only place that touches the terminal, reads the wall clock for drawing,
//! and handles signals.
//!
//! Three sources feed one channel: a thread reading the terminal's bytes, a thread receiving
//! signals, and the simulation's worker (in compare mode, the coordinator of the variants)
//! saying it has a new snapshot. The loop waits on the
//! channel (or until a frame or a held Esc is due), so a key is answered as soon as it
//! arrives whatever the cloth's size: the loop itself only renders and draws.
//!
//! Drawing is paced by the terminal ([`super::link`]): each frame carries a status query and
//! the next waits for its answer, cut to what the link takes in a short while; only the
//! draw rate drops when the terminal falls behind, never the simulation's.
//!
//! However it ends (quit, error, a terminal that went away, SIGTERM, SIGINT, SIGHUP, SIGQUIT,
//! a panic) the terminal is restored first. Ctrl-Z and SIGTSTP leave the terminal as the shell
//! wants it and stop the process; on SIGCONT the loop enters it again and redraws.

use std::io::{self, Write as _};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use anyhow::Context;
use ratatui::crossterm::event::Event;
use ratatui::layout::Rect;

use super::decode::{Decoder, Input};
use super::link::Pacer;
use super::model::{App, Level, Stats};
use super::terminal::{self, TerminalGuard};
use super::{Message, input, layout, panes, update, view};

/// How often the drawing rate refreshes.
const WINDOW: Duration = Duration::from_secs(1);

/// Longest wait for an event when nothing is due.
const IDLE: Duration = Duration::from_millis(500);

/// What woke the loop.
enum Wake {
    /// Bytes from the terminal, or the error reading them (the terminal is gone).
    Input(io::Result<Vec<u8>>),
    /// A signal arrived.
    Signal(i32),
    /// The worker published a snapshot.
    Snapshot,
}

/// How the loop ended.
enum End {
    /// The user quit.
    Quit,
    /// A terminating signal: the process ends as that signal would have ended it.
    Signal(i32),
}

/// Runs `app` in the terminal, drawing at most `fps` frames a second and writing at most
/// `max_rate` bytes a second; restores the terminal however it ends.
///
/// # Errors
/// When the terminal cannot be set up or fails, or the simulation's thread cannot start.
pub fn run(mut app: App, fps: u32, max_rate: Option<u64>) -> anyhow::Result<()> {
    let (tx, rx) = mpsc::channel();
    let signals = signals::watch(tx.clone()).context("cannot watch for signals")?;
    let notify_tx = std::sync::Mutex::new(tx.clone());
    app.start_worker(std::sync::Arc::new(move || {
        if let Ok(tx) = notify_tx.lock() {
            let _ = tx.send(Wake::Snapshot);
        }
    }))?;
    terminal::restore_on_panic();
    let sixteen = app.depth == cloth_render::ColorDepth::Ansi16;
    let mut guard =
        TerminalGuard::enter(app.mouse, sixteen).context("cannot set up the terminal")?;
    spawn_input(tx).context("cannot read the keyboard")?;
    let mut pacer = Pacer::new(max_rate);
    let mut decoder = Decoder::new();
    let end = event_loop(&mut guard, &mut app, (fps, &mut pacer, &mut decoder), &rx);
    // A recording ends with the UI, kept as far as it went.
    let recorded = app.stop_recording();
    // The screen goes back at once; raw mode stays until the answers to the queries still
    // in flight are in, or they would be typed into the shell.
    guard.leave_screen();
    settle(&rx, &mut pacer, &mut decoder);
    guard.leave();
    drop(guard);
    signals.close();
    match recorded {
        Some(Ok(path)) => {
            let _ = writeln!(
                std::io::stderr(),
                "clothsim: the screen recording is in {}",
                path.display()
            );
        }
        Some(Err(e)) => {
            let _ = writeln!(std::io::stderr(), "clothsim: {e:#}");
        }
        None => {}
    }
    match end? {
        End::Quit => Ok(()),
        End::Signal(sig) => {
            // Worker threads end with the process; nothing to save.
            signals::die_of(sig);
            Ok(())
        }
    }
}

/// Reads the terminal's bytes on their own thread (stdin, or the controlling terminal when
/// stdin is not one); a read error or the end of input (the terminal closed) is sent too,
/// and ends the thread.
fn spawn_input(tx: Sender<Wake>) -> io::Result<()> {
    use std::io::{IsTerminal as _, Read as _};
    let mut source: Box<dyn io::Read + Send> = if io::stdin().is_terminal() {
        Box::new(io::stdin())
    } else {
        Box::new(std::fs::File::open(tty_path())?)
    };
    std::thread::Builder::new()
        .name("clothsim-input".to_owned())
        .spawn(move || {
            let mut buf = vec![0u8; 4096];
            loop {
                let got = match source.read(&mut buf) {
                    Ok(0) => Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the terminal closed",
                    )),
                    Ok(n) => Ok(buf[..n].to_vec()),
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                    Err(e) => Err(e),
                };
                let failed = got.is_err();
                if tx.send(Wake::Input(got)).is_err() || failed {
                    return;
                }
            }
        })
        .map(|_| ())
}

/// The controlling terminal's name.
fn tty_path() -> &'static str {
    if cfg!(windows) { "CONIN$" } else { "/dev/tty" }
}

/// Drawing measurements over a window of wall time.
struct Meter {
    start: Instant,
    draws: u32,
    draw_time: Duration,
}

impl Meter {
    fn new(now: Instant) -> Self {
        Self {
            start: now,
            draws: 0,
            draw_time: Duration::ZERO,
        }
    }
}

fn event_loop(
    guard: &mut TerminalGuard,
    app: &mut App,
    (fps, pacer, decoder): (u32, &mut Pacer, &mut Decoder),
    rx: &Receiver<Wake>,
) -> anyhow::Result<End> {
    let interval = Duration::from_secs_f64(1.0 / f64::from(fps));
    let size = guard.terminal.size()?;
    update(
        app,
        Message::Resize {
            width: size.width,
            height: size.height,
        },
    );
    let mut dirty = true;
    // A key's answer is drawn at once, not at the next frame slot (which at `--fps 1` is up
    // to a second away); only the cloth's motion waits for its slot.
    let mut urgent = true;
    let mut next_draw = Instant::now();
    let mut meter = Meter::new(next_draw);
    let mut mouse = app.mouse;
    loop {
        let now = Instant::now();
        let mut until = if dirty { next_draw } else { now + IDLE };
        if urgent {
            until = now;
        }
        if dirty && !pacer.may_draw(now) {
            // Held by the terminal: an answer (on the channel) or the pacer's own time frees it.
            until = pacer.next_check(now).unwrap_or(now + IDLE).max(now);
        }
        if let Some(d) = decoder.deadline() {
            until = until.min(d);
        }
        let first = match rx.recv_timeout(until.saturating_duration_since(now)) {
            Ok(w) => Some(w),
            Err(RecvTimeoutError::Timeout) => None,
            Err(RecvTimeoutError::Disconnected) => anyhow::bail!("the event channel closed"),
        };
        let mut events = Vec::new();
        for wake in first.into_iter().chain(rx.try_iter()) {
            match wake {
                Wake::Input(Ok(bytes)) => {
                    let now = Instant::now();
                    for input in decoder.push(&bytes, now) {
                        match input {
                            Input::Event(ev) => events.push(ev),
                            Input::Answer => pacer.answered(now),
                        }
                    }
                }
                Wake::Input(Err(e)) => {
                    return Err(e).context("the terminal went away");
                }
                Wake::Signal(sig) => match signals::meaning(sig) {
                    signals::Meaning::Stop => {
                        suspend(guard, rx, pacer, decoder)?;
                        dirty = true;
                        urgent = true;
                    }
                    signals::Meaning::Continue => {
                        guard.resume()?;
                        dirty = true;
                        urgent = true;
                    }
                    signals::Meaning::End => return Ok(End::Signal(sig)),
                    signals::Meaning::Resize => {
                        let (width, height) = ratatui::crossterm::terminal::size()?;
                        events.push(Event::Resize(width, height));
                    }
                    signals::Meaning::Ignore => {}
                },
                Wake::Snapshot => {
                    if update::adopt(app) {
                        dirty = true;
                    }
                }
            }
        }
        for input in decoder.expire(Instant::now()) {
            match input {
                Input::Event(ev) => events.push(ev),
                Input::Answer => pacer.answered(Instant::now()),
            }
        }
        for ev in &events {
            if let Some(m) = input::message(app, ev) {
                update(app, m);
                dirty = true;
                urgent = true;
            }
            if app.quit {
                return Ok(End::Quit);
            }
        }
        app.sync();
        if app.suspend {
            app.suspend = false;
            suspend(guard, rx, pacer, decoder)?;
            dirty = true;
            urgent = true;
        }
        if app.mouse != mouse {
            mouse = app.mouse;
            guard.set_mouse(mouse)?;
        }
        if let Some(w) = &app.worker
            && !w.alive()
            && app.sim.fault.is_none()
        {
            anyhow::bail!("the simulation's thread stopped unexpectedly");
        }
        if app.group().is_some_and(|g| !g.alive()) {
            anyhow::bail!("the thread stepping the variants stopped unexpectedly");
        }

        let now = Instant::now();
        let span = now.duration_since(meter.start);
        if span >= WINDOW {
            let s = span.as_secs_f64();
            let stats = Stats {
                rates: app.stats.rates,
                draws_per_sec: f64::from(meter.draws) / s,
                draw_ms: if meter.draws > 0 {
                    meter.draw_time.as_secs_f64() * 1e3 / f64::from(meter.draws)
                } else {
                    0.0
                },
                link: pacer.measure(span, now),
            };
            meter = Meter::new(now);
            if stats != app.stats {
                update(app, Message::Measured(stats));
                dirty = true;
            }
        }

        let due = dirty && (urgent || now >= next_draw);
        if due && !pacer.may_draw(now) {
            pacer.hold(now);
        } else if due {
            let size = guard.terminal.size()?;
            let area = Rect::new(0, 0, size.width, size.height);
            panes::prepare(app, area);
            let pictures = layout::regions(app, area).map_or_else(Vec::new, |r| r.pictures());
            // NOTE: the finished buffer is copied out because the terminal lends it only
            // while it is itself borrowed.
            let drawn = guard.terminal.draw(|f| view(app, f))?.buffer.clone();
            let query = pacer.wants_query();
            let budget = pacer.budget();
            let painted = guard
                .terminal
                .backend_mut()
                .present(&drawn, budget, &pictures, query)?;
            if let Some(r) = app.recording.as_mut()
                && let Err(e) = r.frame(&drawn, now)
            {
                app.recording = None;
                app.say(Level::Error, format!("{e:#}; the recording stopped"));
            }
            pacer.sent(
                painted.bytes,
                query && painted.bytes > 0,
                painted.unfinished,
                now,
            );
            // What the budget left over is drawn as soon as the terminal takes more.
            dirty = painted.unfinished;
            urgent = painted.unfinished;
            if painted.bytes > 0 {
                meter.draws += 1;
            }
            meter.draw_time += now.elapsed();
            // The next frame's slot is a whole interval after this draw, so neither a key's
            // draw nor a late one bunches frames above `fps`.
            next_draw = (next_draw + interval).max(now + interval);
        }
    }
}

/// Waits (at most [`Pacer::settle_time`]) for the answers to the status queries still in
/// flight, so that none reaches the shell as typed text once raw mode is off; returns what
/// else arrived. `decoder` is the loop's, which may hold the start of an answer.
fn settle(rx: &Receiver<Wake>, pacer: &mut Pacer, decoder: &mut Decoder) -> Vec<Wake> {
    let deadline = Instant::now() + pacer.settle_time();
    let mut others = Vec::new();
    while pacer.in_flight() > 0 {
        let Some(left) = deadline.checked_duration_since(Instant::now()) else {
            break;
        };
        match rx.recv_timeout(left) {
            Ok(Wake::Input(Ok(bytes))) => {
                for input in decoder.push(&bytes, Instant::now()) {
                    if input == Input::Answer {
                        pacer.answered(Instant::now());
                    }
                }
            }
            Ok(Wake::Input(Err(_))) | Err(_) => break,
            Ok(other) => others.push(other),
        }
    }
    others
}

/// Leaves the terminal and stops the process as SIGTSTP would; on `fg`, enters it again.
fn suspend(
    guard: &mut TerminalGuard,
    rx: &Receiver<Wake>,
    pacer: &mut Pacer,
    decoder: &mut Decoder,
) -> anyhow::Result<()> {
    guard.leave_screen();
    // What arrives meanwhile (a snapshot, a signal) is of no use to a stopped process but a
    // terminating signal, which ends it now.
    for wake in settle(rx, pacer, decoder) {
        if let Wake::Signal(sig) = wake
            && matches!(signals::meaning(sig), signals::Meaning::End)
        {
            guard.leave();
            signals::die_of(sig);
        }
    }
    guard.leave();
    signals::stop_self();
    guard
        .resume()
        .context("cannot set up the terminal again after a suspend")
}

/// Signals, on Unix through signal-hook: a thread forwards them to the loop's channel.
#[cfg(unix)]
mod signals {
    use std::sync::mpsc::Sender;

    use signal_hook::consts::{SIGCONT, SIGHUP, SIGINT, SIGQUIT, SIGTERM, SIGTSTP, SIGWINCH};
    use signal_hook::iterator::{Handle, Signals};

    use super::Wake;

    /// What a signal asks of the loop.
    pub enum Meaning {
        /// Restore the terminal and stop (SIGTSTP).
        Stop,
        /// Enter the terminal again and redraw (SIGCONT).
        Continue,
        /// Restore the terminal and end (SIGTERM, SIGINT, SIGHUP, SIGQUIT).
        End,
        /// The terminal changed size (SIGWINCH).
        Resize,
        /// Nothing.
        Ignore,
    }

    /// The meaning of `sig`.
    pub fn meaning(sig: i32) -> Meaning {
        match sig {
            SIGTSTP => Meaning::Stop,
            SIGCONT => Meaning::Continue,
            SIGTERM | SIGINT | SIGHUP | SIGQUIT => Meaning::End,
            SIGWINCH => Meaning::Resize,
            _ => Meaning::Ignore,
        }
    }

    /// The watching thread's handle; closing it ends the thread.
    pub struct Watch(Handle);

    impl Watch {
        /// Stops watching.
        pub fn close(&self) {
            self.0.close();
        }
    }

    /// Forwards the signals that concern the terminal to `tx`.
    pub fn watch(tx: Sender<Wake>) -> std::io::Result<Watch> {
        let mut signals =
            Signals::new([SIGTERM, SIGINT, SIGHUP, SIGQUIT, SIGTSTP, SIGCONT, SIGWINCH])?;
        let handle = signals.handle();
        std::thread::Builder::new()
            .name("clothsim-signals".to_owned())
            .spawn(move || {
                for sig in signals.forever() {
                    if tx.send(Wake::Signal(sig)).is_err() {
                        return;
                    }
                }
            })?;
        Ok(Watch(handle))
    }

    /// Stops the process as SIGTSTP's default action would, until SIGCONT.
    pub fn stop_self() {
        let _ = signal_hook::low_level::emulate_default_handler(SIGTSTP);
    }

    /// Ends the process as `sig`'s default action would (the shell sees the signal).
    pub fn die_of(sig: i32) {
        let _ = signal_hook::low_level::emulate_default_handler(sig);
        // Should the default action not end the process, end it with the shell's code for it.
        std::process::exit(128 + sig);
    }
}

/// Without Unix signals: nothing to watch, suspend or re-raise.
#[cfg(not(unix))]
mod signals {
    use std::sync::mpsc::Sender;

    use super::Wake;

    /// What a signal asks of the loop.
    pub enum Meaning {
        /// Restore the terminal and stop.
        Stop,
        /// Enter the terminal again and redraw.
        Continue,
        /// Restore the terminal and end.
        End,
        /// The terminal changed size.
        Resize,
        /// Nothing.
        Ignore,
    }

    /// No signals arrive here.
    pub fn meaning(_sig: i32) -> Meaning {
        Meaning::Ignore
    }

    /// Nothing to close.
    pub struct Watch;

    impl Watch {
        /// Nothing to stop.
        pub fn close(&self) {}
    }

    /// Nothing to watch.
    pub fn watch(_tx: Sender<Wake>) -> std::io::Result<Watch> {
        Ok(Watch)
    }

    /// Suspending is a Unix job-control feature.
    pub fn stop_self() {}

    /// Unreachable without signals.
    pub fn die_of(sig: i32) {
        std::process::exit(128 + sig);
    }
}
