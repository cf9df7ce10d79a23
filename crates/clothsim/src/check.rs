//! `clothsim check`: every solver of this build judged the same way, by the conformance kit
//! (`cloth-check`): the same cases and the same energy-based measures as the course's Verlet,
//! one row per case, exit 1 when any case fails.

use std::sync::Mutex;

use anyhow::Context as _;
use cloth_check::{CaseReport, CheckOptions, Report};
use cloth_solver::{Registry, SolverEntry};
use serde_json::Value;

use crate::args::SolverFlags;

/// Arguments of `clothsim check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A solver to check (repeatable; default: every solver of this build).
    #[arg(long = "solver", value_name = "NAME")]
    solvers: Vec<String>,
    /// A bundled scene to run the cases of (repeatable; default: all of them).
    #[arg(long = "scene", value_name = "NAME")]
    scenes: Vec<String>,
    /// The full set of cases (steps per frame 1, 2, 5, 10 and 30, self-collision on and off),
    /// for nightly runs, instead of the quick set.
    #[arg(long)]
    full: bool,
    /// Only the runs at N steps per frame (repeatable; default: every count of the set, quick or
    /// full); the swap and wind cases are kept.
    #[arg(long = "steps", value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1000))]
    steps: Vec<u32>,
    /// A factor on every case's spring constant (default 1), to see that no verdict hangs on
    /// noise: a bound whose verdict flips at 1.0002 or 0.9998 measures noise, not the solver.
    #[arg(long, value_name = "FACTOR", value_parser = parse_ks_scale)]
    ks_scale: Option<f64>,
    /// Print the reports as JSON (a list, one per solver) instead of the table.
    #[arg(long)]
    json: bool,
    /// Cases run at once, each on a thread of its own (default: one per core). Each case is
    /// held to a time budget measured on one core.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=256))]
    jobs: Option<u16>,
    /// Options of the checked solver: `--option KEY=VALUE`, `--threads`, `--order`.
    #[command(flatten)]
    flags: SolverFlags,
}

/// `--ks-scale`: a finite factor from 0.5 to 2, where the cases stay the cases they are.
fn parse_ks_scale(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(f) if (0.5..=2.0).contains(&f) => Ok(f),
        _ => Err(format!("{text:?} is not a number from 0.5 to 2")),
    }
}

/// Checks every solver asked for and prints each case as it ends, then each solver's summary.
///
/// # Errors
/// A solver that is not registered or refuses its options, a scene that is not bundled, a
/// failed write, and (after everything is printed) any case that failed.
pub fn run(args: &Args, registry: &Registry) -> anyhow::Result<()> {
    let entries: Vec<SolverEntry> = if args.solvers.is_empty() {
        registry.entries().to_vec()
    } else {
        args.solvers
            .iter()
            .map(|name| registry.get(name).copied())
            .collect::<Result<_, _>>()?
    };
    let mut check = CheckOptions {
        scenes: args.scenes.clone(),
        full: args.full,
        steps: args.steps.clone(),
        ks_scale: args.ks_scale.unwrap_or(1.0),
        ..CheckOptions::default()
    };
    if let Some(jobs) = args.jobs {
        check.threads = usize::from(jobs);
    }
    let flags = args.flags.to_flags();
    let mut reports: Vec<Report> = Vec::new();
    for entry in &entries {
        let mut options = serde_json::Map::new();
        for (flag, option, value) in &flags.given {
            if entry.option(option).is_none() {
                anyhow::bail!("{flag}: the {} solver has no {option} option", entry.name());
            }
            options.insert(option.clone(), value.clone());
        }
        let options = Value::Object(options);
        entry
            .check(&options)
            .map_err(|e| anyhow::anyhow!("{}: {e}", entry.name()))?;
        if !args.json {
            say(&format!(
                "check of {} with options {options}\n",
                entry.name()
            ))?;
        }
        // A row is printed as its case ends, so a long check shows its progress; the first
        // failed write ends the printing and is reported after the check.
        let failed_write: Mutex<Option<anyhow::Error>> = Mutex::new(None);
        let mut on_case = |case: &CaseReport| {
            if args.json {
                return;
            }
            let mut failed = failed_write
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            if failed.is_none()
                && let Err(e) = say(&format!("{case}\n"))
            {
                *failed = Some(e);
            }
        };
        let report = cloth_check::check_each(entry, &options, &check, &mut on_case)
            .with_context(|| format!("the check of {}", entry.name()))?;
        if let Some(e) = failed_write
            .into_inner()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
        {
            return Err(e);
        }
        if !args.json {
            let summary = report.to_string();
            let last = summary.lines().last().unwrap_or_default();
            say(&format!("{last}\n"))?;
        }
        reports.push(report);
    }
    if args.json {
        let mut text = serde_json::to_string_pretty(&reports)?;
        text.push('\n');
        say(&text)?;
    }
    let failed: Vec<String> = reports
        .iter()
        .filter(|r| !r.passed())
        .map(|r| format!("{} ({} cases)", r.solver, r.failures().count()))
        .collect();
    if !failed.is_empty() {
        anyhow::bail!(
            "the check failed for {}: see the rows marked FAIL, TOO SLOW or PASSES NOW above",
            failed.join(", ")
        );
    }
    Ok(())
}

/// Writes `text` to standard output at once, so rows appear as cases end. The kit reports cases
/// from its own threads: each write takes standard output for itself and gives it back.
fn say(text: &str) -> anyhow::Result<()> {
    let mut out = cloth_run::output::Stdout::new();
    out.write_all_or_fail(text.as_bytes())?;
    out.finish()
}
