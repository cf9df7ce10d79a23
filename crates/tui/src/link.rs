//! Drawing paced by what the terminal has taken, not by what was written.
//!
//! Over SSH a write returns as soon as the bytes are in a buffer, and the channel and socket
//! buffers hold hundreds of kilobytes: a UI that draws whenever its write returns fills them,
//! and a key's answer then waits behind seconds of old frames. A terminal answers the status
//! query (`ESC [ 6 n`) only once it has taken every byte written before it, so the time from
//! a frame's write to the answer of the query that follows it is how long that frame took to
//! reach the far end.
//!
//! The [`Pacer`] keeps about one frame in flight: after a frame and its query, the next frame
//! waits for the answer. Each answer also measures the link (bytes over round trip), and a
//! frame is cut to what the link takes in [`TARGET`] (the rest follows in the next frames,
//! the text before the cloth), so a key's answer is on screen within about two round
//! trips and two targets. Only drawing slows down: the simulation runs on at its own rate.
//!
//! A `--max-rate` caps the bytes per second by hand, as a token bucket. A terminal that never
//! answers (a few do not know the query) is found out after [`SILENT`] and drawn unpaced, as
//! before.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// How long the bytes of one frame may take to cross the link.
pub const TARGET: Duration = Duration::from_millis(80);

/// A frame is never cut below this many bytes (a header line and a note fit).
pub const SMALLEST: usize = 512;

/// With no answer yet to any query for this long, the terminal is taken not to answer.
pub const SILENT: Duration = Duration::from_secs(5);

/// An unanswered query older than this no longer holds drawing back (its answer was lost);
/// its answer, should it come, is matched in order all the same.
pub const LOST: Duration = Duration::from_secs(10);

/// Round trips below this are treated as this (a local terminal answers in microseconds).
const QUICKEST: Duration = Duration::from_micros(200);

/// A query written and not yet answered.
#[derive(Debug, Clone, Copy)]
struct Query {
    sent: Instant,
    bytes: usize,
}

/// What the pacer says of the last while, for the header.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measure {
    /// Whether drawing was held back or cut by the terminal (or `--max-rate`) in the while.
    pub limited: bool,
    /// Whether it was `--max-rate` that held it.
    pub by_cap: bool,
    /// Bytes written per second over the while.
    pub bytes_per_sec: f64,
}

/// Decides when to draw and how much, from the answers to status queries.
#[derive(Debug, Clone)]
pub struct Pacer {
    queries: VecDeque<Query>,
    /// Whether any query was ever answered.
    answering: bool,
    /// Whether the terminal was found not to answer.
    silent: bool,
    /// When the first query went out.
    first: Option<Instant>,
    /// The link's rate, bytes per second, from the answers (smoothed).
    rate: Option<f64>,
    /// The link's latency: the shortest round trip of a frame too small to load the link.
    latency: Option<Duration>,
    /// The last answer's round trip.
    last_trip: Option<Duration>,
    /// `--max-rate`, bytes per second.
    cap: Option<f64>,
    /// The cap's token bucket: bytes that may be written now (negative: owed).
    tokens: f64,
    refilled: Option<Instant>,
    /// Since the last [`Self::measure`]: bytes written, frames cut, time a due frame waited.
    written: usize,
    cut: usize,
    held: Duration,
    /// When the frame now waiting fell due.
    due: Option<Instant>,
    held_by_cap: bool,
}

impl Pacer {
    /// A pacer that has measured nothing yet, capped at `cap` bytes per second if given.
    pub fn new(cap: Option<u64>) -> Self {
        Self {
            queries: VecDeque::new(),
            answering: false,
            silent: false,
            first: None,
            rate: None,
            latency: None,
            last_trip: None,
            cap: cap.map(|c| c as f64),
            tokens: 0.0,
            refilled: None,
            written: 0,
            cut: 0,
            held: Duration::ZERO,
            due: None,
            held_by_cap: false,
        }
    }

    fn refill(&mut self, now: Instant) {
        if let Some(cap) = self.cap {
            let since = self
                .refilled
                .map_or(Duration::ZERO, |t| now.saturating_duration_since(t));
            // The bucket holds at most one target's worth: a pause does not bank a burst.
            self.tokens = (self.tokens + cap * since.as_secs_f64()).min(cap * TARGET.as_secs_f64());
            self.refilled = Some(now);
        }
    }

    fn waiting(&self, now: Instant) -> bool {
        !self.silent
            && self
                .queries
                .front()
                .is_some_and(|q| now.saturating_duration_since(q.sent) < LOST)
    }

    /// Whether a frame may be written at `now`; when not, the caller tries again at
    /// [`Self::next_check`] or when an answer comes.
    pub fn may_draw(&mut self, now: Instant) -> bool {
        self.notice_silence(now);
        self.refill(now);
        let capped = self.cap.is_some() && self.tokens < 0.0;
        !(self.waiting(now) || capped)
    }

    /// A frame fell due at `now` and [`Self::may_draw`] said no: the wait counts as drawing
    /// limited by the terminal (or the cap) until the frame goes out.
    pub fn hold(&mut self, now: Instant) {
        if self.due.is_none() {
            self.due = Some(now);
            self.held_by_cap |= !self.waiting(now);
        }
    }

    /// Most bytes the next frame may take (`None`: all it needs).
    pub fn budget(&self) -> Option<usize> {
        let target = TARGET.as_secs_f64();
        let by_link = if self.silent || !self.answering {
            None
        } else {
            self.rate.map(|r| {
                // NOTE: the rate was measured over whole round trips, latency included; the
                // latency is added back so that a distant link's budget settles at its
                // bandwidth times the target rather than shrinking to the smallest frame.
                let window = target + self.latency.map_or(0.0, |d| d.as_secs_f64());
                r * window
            })
        };
        let by_cap = self.cap.map(|c| c * target);
        let b = match (by_link, by_cap) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        b.map(|b| (b as usize).max(SMALLEST))
    }

    /// Whether the frame about to be written should carry a status query.
    pub fn wants_query(&self) -> bool {
        !self.silent && self.queries.is_empty()
    }

    /// A frame of `bytes` went out at `now` (with a query when `queried`); `cut` when the
    /// budget left cells for later.
    pub fn sent(&mut self, bytes: usize, queried: bool, cut: bool, now: Instant) {
        self.written += bytes;
        if let Some(due) = self.due.take() {
            self.held += now.saturating_duration_since(due);
        }
        if cut {
            self.cut += 1;
            self.held_by_cap |= self.cap.is_some_and(|c| self.rate.is_none_or(|r| c < r));
        }
        if self.cap.is_some() {
            self.refill(now);
            self.tokens -= bytes as f64;
        }
        if queried {
            self.first.get_or_insert(now);
            self.queries.push_back(Query { sent: now, bytes });
        }
    }

    /// An answer came at `now`: it answers the oldest query.
    pub fn answered(&mut self, now: Instant) {
        self.answering = true;
        self.silent = false;
        let Some(q) = self.queries.pop_front() else {
            return;
        };
        let trip = now.saturating_duration_since(q.sent).max(QUICKEST);
        self.last_trip = Some(trip);
        if q.bytes < SMALLEST {
            self.latency = Some(self.latency.map_or(trip, |s| s.min(trip)));
        }
        // Only frames big enough to load the link measure it; a small one mostly measures
        // the latency.
        let loaded = self.budget().is_none_or(|b| q.bytes * 2 >= b) && q.bytes >= SMALLEST;
        if loaded {
            let sample = q.bytes as f64 / trip.as_secs_f64();
            self.rate = Some(match self.rate {
                // A drop is taken at once (the link is slower than thought); a rise smoothly.
                Some(r) if sample > r => r + 0.5 * (sample - r),
                _ => sample,
            });
        }
    }

    fn notice_silence(&mut self, now: Instant) {
        if !self.answering
            && !self.silent
            && self
                .first
                .is_some_and(|t| now.saturating_duration_since(t) >= SILENT)
        {
            self.silent = true;
            self.queries.clear();
        }
    }

    /// When to look again while drawing is held: a query becoming lost, the terminal
    /// found silent, or the cap's bucket refilled.
    pub fn next_check(&self, now: Instant) -> Option<Instant> {
        let mut at: Option<Instant> = None;
        let mut earliest = |t: Instant| at = Some(at.map_or(t, |a| a.min(t)));
        if let Some(q) = self.queries.front()
            && !self.silent
        {
            earliest(q.sent + LOST);
            if !self.answering
                && let Some(f) = self.first
            {
                earliest(f + SILENT);
            }
        }
        if let Some(cap) = self.cap
            && self.tokens < 0.0
        {
            earliest(now + Duration::from_secs_f64(-self.tokens / cap));
        }
        at
    }

    /// Status queries written and not answered (none once the terminal is found silent).
    pub fn in_flight(&self) -> usize {
        if self.silent { 0 } else { self.queries.len() }
    }

    /// How long the answers in flight may still take: a few of the last round trips, from
    /// 20 ms to half a second (keys typed meanwhile are read and dropped, so it stays short).
    pub fn settle_time(&self) -> Duration {
        self.last_trip.map_or(Duration::from_millis(500), |t| {
            (t * 4).clamp(Duration::from_millis(20), Duration::from_millis(500))
        })
    }

    /// Whether the terminal was found not to answer status queries.
    #[cfg(test)]
    pub fn silent(&self) -> bool {
        self.silent
    }

    /// What happened over the `span` up to `now` since the last call; starts a new while.
    /// Drawing counts as limited when frames were cut or due frames waited a tenth of it.
    pub fn measure(&mut self, span: Duration, now: Instant) -> Measure {
        let mut held = self.held;
        if let Some(due) = self.due {
            held += now.saturating_duration_since(due);
            self.due = Some(now);
        }
        let limited = self.cut > 0 || held >= span / 10;
        let m = Measure {
            limited,
            by_cap: limited && self.held_by_cap,
            bytes_per_sec: self.written as f64 / span.as_secs_f64().max(1e-9),
        };
        self.written = 0;
        self.cut = 0;
        self.held = Duration::ZERO;
        self.held_by_cap = false;
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(t0: Instant, n: u64) -> Instant {
        t0 + Duration::from_millis(n)
    }

    #[test]
    fn one_frame_is_in_flight_until_its_answer() {
        let t0 = Instant::now();
        let mut p = Pacer::new(None);
        assert!(p.may_draw(t0));
        assert!(p.wants_query());
        p.sent(10_000, true, false, t0);
        assert!(!p.may_draw(ms(t0, 100)));
        assert!(!p.wants_query());
        p.answered(ms(t0, 200));
        assert!(p.may_draw(ms(t0, 200)));
    }

    #[test]
    fn the_budget_is_what_the_link_takes_in_the_target_time() {
        // 16 KB/s and no latency: a 16 000-byte frame answers after a second.
        let t0 = Instant::now();
        let mut p = Pacer::new(None);
        assert_eq!(p.budget(), None, "nothing measured: no limit");
        p.sent(16_000, true, false, t0);
        p.answered(ms(t0, 1000));
        assert_eq!(p.budget(), Some((16_000.0 * TARGET.as_secs_f64()) as usize));
        // A slower link is believed at once.
        p.sent(16_000, true, false, ms(t0, 1000));
        p.answered(ms(t0, 3000));
        assert_eq!(p.budget(), Some((8_000.0 * TARGET.as_secs_f64()) as usize));
    }

    #[test]
    fn a_distant_link_keeps_a_budget_of_its_bandwidth_not_the_smallest_frame() {
        // 1 MB/s, 150 ms away: without the latency the budget would shrink to nothing.
        let t0 = Instant::now();
        let (rate, latency) = (1.0e6, 0.150);
        let mut p = Pacer::new(None);
        let mut now = t0;
        // A small frame (a header line) measures the latency.
        p.sent(200, true, false, now);
        now += Duration::from_secs_f64(latency + 200.0 / rate);
        p.answered(now);
        let mut bytes = 200_000;
        for _ in 0..40 {
            p.sent(bytes, true, true, now);
            now += Duration::from_secs_f64(latency + bytes as f64 / rate);
            p.answered(now);
            bytes = p.budget().unwrap();
        }
        let want = rate * TARGET.as_secs_f64();
        assert!(
            (bytes as f64 - want).abs() < 0.05 * want,
            "{bytes} vs {want}"
        );
    }

    #[test]
    fn the_budget_converges_on_the_link_times_the_target() {
        let t0 = Instant::now();
        let rate = 16_384.0;
        let mut p = Pacer::new(None);
        let mut now = t0;
        let mut bytes = 20_000;
        for _ in 0..30 {
            assert!(p.may_draw(now));
            p.sent(bytes, true, true, now);
            now += Duration::from_secs_f64(bytes as f64 / rate);
            p.answered(now);
            bytes = p.budget().unwrap();
        }
        let want = rate * TARGET.as_secs_f64();
        assert!(
            (bytes as f64 - want).abs() < 0.05 * want,
            "{bytes} vs {want}"
        );
    }

    #[test]
    fn a_terminal_that_never_answers_is_drawn_unpaced_after_a_while() {
        let t0 = Instant::now();
        let mut p = Pacer::new(None);
        p.sent(1000, true, false, t0);
        assert!(!p.may_draw(ms(t0, 100)));
        assert_eq!(p.next_check(ms(t0, 100)), Some(t0 + SILENT));
        assert!(p.may_draw(t0 + SILENT));
        assert!(p.silent());
        assert!(!p.wants_query());
        assert_eq!(p.budget(), None);
    }

    #[test]
    fn the_cap_holds_bytes_per_second_to_the_given_rate() {
        let t0 = Instant::now();
        let cap = 8_000;
        let mut p = Pacer::new(Some(cap));
        let mut now = t0;
        let mut total = 0;
        while now < t0 + Duration::from_secs(10) {
            if p.may_draw(now) {
                let b = p.budget().unwrap();
                assert!(b <= (cap as f64 * TARGET.as_secs_f64()) as usize + SMALLEST);
                p.sent(b, false, true, now);
                total += b;
            } else {
                p.hold(now);
            }
            now += Duration::from_millis(5);
        }
        // 10 s at the cap, plus at most one frame's overdraw.
        let most = 10 * cap as usize + SMALLEST.max(640);
        assert!(total <= most, "{total} > {most}");
        assert!(total >= 9 * cap as usize, "{total}");
        assert!(p.measure(Duration::from_secs(10), now).by_cap);
    }

    #[test]
    fn drawing_is_limited_only_when_due_frames_wait_or_are_cut() {
        let t0 = Instant::now();
        let mut p = Pacer::new(None);
        // A local terminal: every answer within a millisecond, frames never wait long.
        let mut now = t0;
        for _ in 0..30 {
            assert!(p.may_draw(now));
            p.sent(5000, true, false, now);
            now += Duration::from_millis(1);
            assert!(!p.may_draw(now));
            p.hold(now);
            now += Duration::from_micros(500);
            p.answered(now);
            p.sent(0, false, false, now);
            now += Duration::from_millis(32);
        }
        assert!(!p.measure(now - t0, now).limited);
        // A slow one: each due frame waits 100 ms for the answer.
        let t1 = now;
        for _ in 0..10 {
            p.sent(5000, true, false, now);
            p.hold(now);
            now += Duration::from_millis(100);
            p.answered(now);
        }
        let m = p.measure(now - t1, now);
        assert!(m.limited && !m.by_cap, "{m:?}");
    }

    #[test]
    fn a_lost_answer_stops_holding_drawing_back() {
        let t0 = Instant::now();
        let mut p = Pacer::new(None);
        p.sent(100, true, false, t0);
        p.answered(ms(t0, 5));
        p.sent(100, true, false, ms(t0, 10));
        assert!(!p.may_draw(ms(t0, 20)));
        assert!(p.may_draw(ms(t0, 10) + LOST));
    }
}
