//! What a check found: one row per case, each measure with its value and bound.

use std::fmt;

use serde::Serialize;
use serde_json::Value;

/// How one measure came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Outcome {
    /// Within its bound.
    Pass,
    /// Outside its bound.
    Fail,
    /// Outside its bound, as the list of expected failures says.
    ExpectedFail,
    /// Within its bound although the list of expected failures says it fails: the list must
    /// lose that entry (a failure of the check).
    PassesNow,
}

/// One measure of a case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measure {
    /// The measure's name (`energy peak`, `stretch`, ...), as in the list of expected failures.
    pub name: String,
    /// The measured figure, in `unit`.
    pub value: f64,
    /// The bound it is held to, in `unit`.
    pub bound: f64,
    /// The unit of both (`J`, `m/s`, `s`; empty for ratios and counts).
    pub unit: String,
    /// Whether the value must be at least the bound (otherwise at most).
    pub at_least: bool,
    /// How it came out.
    pub outcome: Outcome,
}

impl Measure {
    /// A measure whose `value` must be at most `bound`.
    pub(crate) fn at_most(name: &str, value: f64, bound: f64, unit: &str) -> Self {
        let pass = value <= bound;
        Self::with(name, value, bound, unit, false, pass)
    }

    /// A measure whose `value` must be at least `bound`.
    pub(crate) fn at_least(name: &str, value: f64, bound: f64, unit: &str) -> Self {
        let pass = value >= bound;
        Self::with(name, value, bound, unit, true, pass)
    }

    fn with(name: &str, value: f64, bound: f64, unit: &str, at_least: bool, pass: bool) -> Self {
        Self {
            name: name.to_owned(),
            value,
            bound,
            unit: unit.to_owned(),
            at_least,
            outcome: if pass { Outcome::Pass } else { Outcome::Fail },
        }
    }

    /// Whether the measured value is within its bound (before the list of expected failures).
    #[must_use]
    pub fn within(&self) -> bool {
        matches!(self.outcome, Outcome::Pass | Outcome::PassesNow)
    }
}

/// How a case came out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Verdict {
    /// Every measure within its bound.
    Pass,
    /// A measure outside its bound that the list does not expect, or a listed one that passes
    /// now.
    Fail,
    /// Only measures that the list of expected failures names are outside their bounds.
    ExpectedFail,
    /// Stopped at its time budget (and not expected to be).
    TooSlow,
    /// Not run: the case is outside what the solver declares it can do (an explicit solver
    /// beyond its stability limit).
    Skipped,
}

impl Verdict {
    /// Whether this verdict fails the check.
    #[must_use]
    pub fn fails(self) -> bool {
        matches!(self, Verdict::Fail | Verdict::TooSlow)
    }

    fn label(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "FAIL",
            Verdict::ExpectedFail => "expected-fail",
            Verdict::TooSlow => "TOO-SLOW",
            Verdict::Skipped => "skipped",
        }
    }
}

/// One case: what was run and how each measure came out.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseReport {
    /// The case's name, as in the list of expected failures
    /// (`sphere / 1 step / limit on / self-collision on / ks 5000`, `pinned4 / swap at frame
    /// 10`).
    pub id: String,
    /// The bundled scene.
    pub scene: String,
    /// Steps per frame of the run (of the solver, for a swap case).
    pub steps_per_frame: u32,
    /// Whether the stretch limit was on (`None` for a swap case, which takes the scene's).
    pub stretch_limit: Option<bool>,
    /// Whether self-collision was on (`None` for a swap case, which takes the scene's).
    pub self_collision: Option<bool>,
    /// The spring constant of the case, N/m, before any perturbation of the check.
    pub ks: f64,
    /// The frame of Verlet's run at which a swap case swaps.
    pub swap_frame: Option<usize>,
    /// The wind of the wind case, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wind: Option<[f64; 3]>,
    /// The measures, in the order of the crate's documentation.
    pub measures: Vec<Measure>,
    /// How the case came out.
    pub verdict: Verdict,
    /// Why the case was skipped, stopped or failed to run, when it was.
    pub note: Option<String>,
}

impl CaseReport {
    /// The measure called `name`.
    #[must_use]
    pub fn measure(&self, name: &str) -> Option<&Measure> {
        self.measures.iter().find(|m| m.name == name)
    }

    /// Sets the verdict from the measures' outcomes.
    pub(crate) fn judge(&mut self) {
        if self.verdict == Verdict::Skipped {
            return;
        }
        let failed = |m: &Measure| matches!(m.outcome, Outcome::Fail | Outcome::PassesNow);
        self.verdict = if self
            .measures
            .iter()
            .any(|m| m.name == crate::kit::TIME && m.outcome == Outcome::Fail)
        {
            Verdict::TooSlow
        } else if self.measures.iter().any(failed) {
            Verdict::Fail
        } else if (self.measures.iter()).any(|m| m.outcome == Outcome::ExpectedFail) {
            Verdict::ExpectedFail
        } else {
            Verdict::Pass
        };
    }
}

/// A whole check of one solver: every case, in order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Report {
    /// The solver's name.
    pub solver: String,
    /// The options it was built with.
    pub options: Value,
    /// Whether this was the full set of cases (else the quick one).
    pub full: bool,
    /// The factor on every case's spring constant (1 unless the check was perturbed).
    pub ks_scale: f64,
    /// The cases.
    pub cases: Vec<CaseReport>,
    /// Wall-clock seconds of the whole check.
    pub seconds: f64,
}

impl Report {
    /// Whether no case failed: every case passed, failed as expected or was skipped.
    #[must_use]
    pub fn passed(&self) -> bool {
        !self.cases.iter().any(|c| c.verdict.fails())
    }

    /// The cases that fail the check.
    pub fn failures(&self) -> impl Iterator<Item = &CaseReport> {
        self.cases.iter().filter(|c| c.verdict.fails())
    }
}

/// A number in a few significant digits, for the table.
fn short(x: f64) -> String {
    if x == 0.0 {
        "0".to_owned()
    } else if !x.is_finite() {
        format!("{x}")
    } else if (1e-3..1e5).contains(&x.abs()) {
        let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.2e}")
    }
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let relation = if self.at_least { ">=" } else { "<=" };
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        let mark = match self.outcome {
            Outcome::Pass => "",
            Outcome::Fail => " FAIL",
            Outcome::ExpectedFail => " (expected)",
            Outcome::PassesNow => " PASSES NOW: remove it from the list",
        };
        write!(
            f,
            "{} {} {relation} {}{unit}{mark}",
            self.name,
            short(self.value),
            short(self.bound)
        )
    }
}

impl fmt::Display for CaseReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let switch = |s: Option<bool>| match s {
            Some(true) => "on",
            Some(false) => "off",
            None => "-",
        };
        let what = match (self.swap_frame, self.wind) {
            (Some(at), _) => format!("swap@{at}"),
            (None, Some(_)) => "wind".to_owned(),
            (None, None) => "run".to_owned(),
        };
        write!(
            f,
            "{:<13} {:<8} {:>5} {:>5} {:>5} {:>8} {:<13}",
            self.scene,
            what,
            self.steps_per_frame,
            switch(self.stretch_limit),
            switch(self.self_collision),
            short(self.ks),
            self.verdict.label()
        )?;
        let measures: Vec<String> = self.measures.iter().map(ToString::to_string).collect();
        write!(f, " {}", measures.join("; "))?;
        if let Some(note) = &self.note {
            write!(f, " [{note}]")?;
        }
        Ok(())
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "check of {} with options {} ({} set{})",
            self.solver,
            self.options,
            if self.full { "full" } else { "quick" },
            if self.ks_scale == 1.0 {
                String::new()
            } else {
                format!(", ks x {}", self.ks_scale)
            }
        )?;
        writeln!(
            f,
            "{:<13} {:<8} {:>5} {:>5} {:>5} {:>8} {:<13} measures",
            "scene", "case", "steps", "limit", "self", "ks", "verdict"
        )?;
        for case in &self.cases {
            writeln!(f, "{case}")?;
        }
        let count = |v: Verdict| self.cases.iter().filter(|c| c.verdict == v).count();
        write!(
            f,
            "{} cases: {} pass, {} fail, {} too slow, {} expected failures, {} skipped, in {:.1} s: {}",
            self.cases.len(),
            count(Verdict::Pass),
            count(Verdict::Fail),
            count(Verdict::TooSlow),
            count(Verdict::ExpectedFail),
            count(Verdict::Skipped),
            self.seconds,
            if self.passed() { "passed" } else { "FAILED" }
        )
    }
}

impl Report {
    /// Every measure outside its bound, listed or not, in the form of the list of expected
    /// failures, for rewriting the list.
    #[must_use]
    pub fn to_expected(&self) -> Vec<crate::ExpectedFailure> {
        let mut out = Vec::new();
        for case in &self.cases {
            for m in &case.measures {
                if matches!(m.outcome, Outcome::Fail | Outcome::ExpectedFail) {
                    out.push(crate::ExpectedFailure {
                        solver: self.solver.clone(),
                        case: case.id.clone(),
                        measure: m.name.clone(),
                        figure: m.value,
                    });
                }
            }
        }
        out
    }
}
