//! The app loop: the only place that reads the clock or touches the terminal.
//!
//! Each turn: wait for input until the next frame is due, turn events into messages, give the
//! simulation the wall time that passed (it owes `wall * rate` simulated seconds, paid in fixed
//! steps of `dt`), run owed steps for at most the budget of a frame interval and forgive the
//! rest (the status line then shows a real-time factor below 1), and draw if anything changed
//! and a frame is due. So however slow the simulation, input and drawing keep their pace.
//!
//! The budget adapts: it is the frame interval minus what drawing measurably costs (with a
//! margin for input), between [`MIN_BUDGET`] and [`MAX_BUDGET`] of the interval. A fixed 55 %
//! would waste idle time when drawing is cheap (pinned4's solver alone needs about two
//! thirds of real time on one core), and starve drawing when it is not.

use std::io::stdout;
use std::time::{Duration, Instant};

use anyhow::Context;
use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{self, DisableMouseCapture, EnableMouseCapture};
use ratatui::crossterm::terminal::{BeginSynchronizedUpdate, EndSynchronizedUpdate};
use ratatui::crossterm::{execute, queue};
use ratatui::layout::Rect;

use super::model::{App, Stats};
use super::{Message, input, panes, update, view};

/// Smallest share of a frame interval the simulation gets.
pub const MIN_BUDGET: f64 = 0.3;
/// Largest share of a frame interval the simulation gets; the rest is always left for input
/// and drawing.
pub const MAX_BUDGET: f64 = 0.8;
/// Wall time kept free for reading input and for jitter, besides the measured drawing cost.
const MARGIN: Duration = Duration::from_millis(2);

/// How often the measurements refresh.
const WINDOW: Duration = Duration::from_secs(1);

/// How long to sleep waiting for input when nothing is running or pending.
const IDLE: Duration = Duration::from_millis(500);

/// Runs `app` in the terminal at most `fps` frames per second; restores the terminal however
/// it ends (a panic too: ratatui's hook restores it, ours releases the mouse first).
pub fn run(mut app: App, fps: u32) -> anyhow::Result<()> {
    let mut terminal = match ratatui::try_init() {
        Ok(t) => t,
        Err(e) => {
            ratatui::restore();
            return Err(e).context("cannot set up the terminal");
        }
    };
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let _ = execute!(stdout(), DisableMouseCapture);
        previous(info);
    }));
    let result = execute!(stdout(), EnableMouseCapture)
        .context("cannot enable the mouse")
        .and_then(|()| event_loop(&mut terminal, &mut app, fps));
    let _ = execute!(stdout(), DisableMouseCapture);
    ratatui::restore();
    result
}

/// Measurements over a window of wall time.
struct Meter {
    start: Instant,
    steps: u64,
    sim_time: f64,
    draws: u32,
    draw_time: Duration,
    lagging: bool,
}

impl Meter {
    fn new(now: Instant) -> Self {
        Self {
            start: now,
            steps: 0,
            sim_time: 0.0,
            draws: 0,
            draw_time: Duration::ZERO,
            lagging: false,
        }
    }

    /// The stats when the window is over (and a new window).
    fn take(&mut self, now: Instant, budget: Duration) -> Option<Stats> {
        let wall = now.duration_since(self.start);
        if wall < WINDOW {
            return None;
        }
        let s = wall.as_secs_f64();
        let stats = Stats {
            realtime_factor: self.sim_time / s,
            steps_per_sec: self.steps as f64 / s,
            draws_per_sec: f64::from(self.draws) / s,
            lagging: self.lagging,
            draw_ms: if self.draws > 0 {
                self.draw_time.as_secs_f64() * 1e3 / f64::from(self.draws)
            } else {
                0.0
            },
            budget_ms: budget.as_secs_f64() * 1e3,
        };
        *self = Self::new(now);
        Some(stats)
    }
}

fn event_loop(terminal: &mut DefaultTerminal, app: &mut App, fps: u32) -> anyhow::Result<()> {
    let interval = Duration::from_secs_f64(1.0 / f64::from(fps));
    let mut budget = interval.mul_f64(MAX_BUDGET);
    // Smoothed cost of one draw (exponential average over about 8 frames).
    let mut draw_cost = Duration::ZERO;
    let size = terminal.size()?;
    update(
        app,
        Message::Resize {
            width: size.width,
            height: size.height,
        },
    );
    let mut dirty = true;
    let mut last_tick = Instant::now();
    let mut next_draw = last_tick;
    let mut meter = Meter::new(last_tick);
    loop {
        let now = Instant::now();
        let timeout = if app.running || dirty {
            next_draw.saturating_duration_since(now)
        } else {
            IDLE
        };
        if event::poll(timeout)? {
            loop {
                let ev = event::read()?;
                if let Some(m) = input::message(app, &ev) {
                    update(app, m);
                    dirty = true;
                }
                if app.quit {
                    return Ok(());
                }
                if !event::poll(Duration::ZERO)? {
                    break;
                }
            }
        }

        let now = Instant::now();
        update(app, Message::Tick(now.duration_since(last_tick)));
        last_tick = now;
        let deadline = now + budget;
        let before = app.sim.time;
        let steps = update::run_owed(app, &mut || Instant::now() < deadline);
        if steps > 0 || app.sim.fault.is_some() && app.overlay == super::model::Overlay::Fault {
            dirty = true;
        }
        meter.steps += steps;
        // A reset during the window makes time go back; count only forward progress.
        meter.sim_time += (app.sim.time - before).max(0.0);
        if app.running && app.debt >= app.sim.dt() {
            // Out of budget: forgive the debt instead of letting it snowball.
            app.debt = 0.0;
            meter.lagging = true;
        }
        if let Some(stats) = meter.take(now, budget)
            && stats != app.stats
        {
            update(app, Message::Measured(stats));
            dirty = true;
        }

        let now = Instant::now();
        if dirty && now >= next_draw {
            let size = terminal.size()?;
            panes::prepare(app, Rect::new(0, 0, size.width, size.height));
            queue!(terminal.backend_mut(), BeginSynchronizedUpdate)?;
            terminal.draw(|f| view(app, f))?;
            execute!(terminal.backend_mut(), EndSynchronizedUpdate)?;
            dirty = false;
            let cost = now.elapsed();
            meter.draws += 1;
            meter.draw_time += cost;
            draw_cost = (draw_cost * 7 + cost) / 8;
            budget = interval
                .saturating_sub(draw_cost + MARGIN)
                .clamp(interval.mul_f64(MIN_BUDGET), interval.mul_f64(MAX_BUDGET));
            next_draw += interval;
            if next_draw < now {
                next_draw = now + interval;
            }
        }
    }
}
