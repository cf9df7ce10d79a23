//! The list of what solvers fail today, beside the kit: `expected-failures.json`.

use serde::{Deserialize, Serialize};

use crate::CheckError;
use crate::report::{CaseReport, Outcome};

/// The file, in the crate's folder.
pub(crate) const FILE: &str = "expected-failures.json";

/// One measure of one case that a solver is known to fail, with the figure it failed with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExpectedFailure {
    /// The solver's name.
    pub solver: String,
    /// The case's name ([`CaseReport::id`]).
    pub case: String,
    /// The measure's name ([`Measure::name`](crate::Measure::name)).
    pub measure: String,
    /// The measured value when it was listed, in the measure's unit.
    pub figure: f64,
}

/// The list kept in the crate.
pub(crate) fn load() -> Result<Vec<ExpectedFailure>, CheckError> {
    serde_json::from_str(include_str!("../expected-failures.json")).map_err(|e| CheckError::Data {
        file: FILE,
        reason: e.to_string(),
    })
}

/// Marks the measures of `case` that `list` names for `solver`: a failure listed is expected,
/// a pass listed passes now (which fails the check until the entry goes).
///
/// NOTE: a listed case that was too slow and now keeps to its budget is not held to "passes
/// now": its time moves with the machine's load by more than the margin of a borderline case,
/// so that verdict would flip from run to run. Its physics measures, now computed over the whole
/// run, are held to their bounds as any case's are. Likewise the listed measures of a case
/// stopped at its budget are not held to "passes now".
pub(crate) fn apply(list: &[ExpectedFailure], solver: &str, case: &mut CaseReport) {
    // A case stopped at its budget measured part of its run: a listed measure that passes
    // over that part says nothing of the whole, so it is not "passes now" either.
    let stopped = case
        .measures
        .iter()
        .any(|m| m.name == crate::kit::TIME && m.outcome == Outcome::Fail);
    for m in &mut case.measures {
        let listed = list
            .iter()
            .any(|e| e.solver == solver && e.case == case.id && e.measure == m.name);
        if listed {
            m.outcome = match m.outcome {
                Outcome::Fail | Outcome::ExpectedFail => Outcome::ExpectedFail,
                Outcome::Pass if stopped || m.name == crate::kit::TIME => Outcome::Pass,
                Outcome::Pass | Outcome::PassesNow => Outcome::PassesNow,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{Measure, Verdict};

    #[test]
    fn the_list_in_the_tree_parses_and_names_each_measure_once() {
        let list = load().unwrap();
        for (i, a) in list.iter().enumerate() {
            assert!(
                !list[..i]
                    .iter()
                    .any(|b| (&b.solver, &b.case, &b.measure) == (&a.solver, &a.case, &a.measure)),
                "listed twice: {a:?}"
            );
        }
    }

    #[test]
    fn a_listed_failure_is_expected_and_a_listed_pass_fails_the_check() {
        let case = |value: f64| CaseReport {
            id: "pinned4 / swap at frame 10".to_owned(),
            scene: "pinned4".to_owned(),
            steps_per_frame: 1,
            stretch_limit: None,
            self_collision: None,
            ks: 5000.0,
            swap_frame: Some(10),
            wind: None,
            measures: vec![Measure::at_most("swap", value, 0.05, "")],
            verdict: Verdict::Pass,
            note: None,
        };
        let list = vec![ExpectedFailure {
            solver: "mine".to_owned(),
            case: "pinned4 / swap at frame 10".to_owned(),
            measure: "swap".to_owned(),
            figure: 0.5,
        }];
        let mut failing = case(0.5);
        apply(&list, "mine", &mut failing);
        failing.judge();
        assert_eq!(failing.verdict, Verdict::ExpectedFail);
        let mut passing = case(0.01);
        apply(&list, "mine", &mut passing);
        passing.judge();
        assert_eq!(passing.verdict, Verdict::Fail);
        assert_eq!(passing.measures[0].outcome, Outcome::PassesNow);
        let mut other = case(0.5);
        apply(&list, "another", &mut other);
        other.judge();
        assert_eq!(other.verdict, Verdict::Fail);
    }

    #[test]
    fn a_listed_time_or_a_measure_of_a_stopped_case_that_passes_is_not_passes_now() {
        let case = |time: f64, rise: f64| CaseReport {
            id: "hammock / 1 step".to_owned(),
            scene: "hammock".to_owned(),
            steps_per_frame: 1,
            stretch_limit: Some(true),
            self_collision: Some(true),
            ks: 5000.0,
            swap_frame: None,
            wind: None,
            measures: vec![
                Measure::at_most("energy rise", rise, 3.0, "J"),
                Measure::at_most(crate::kit::TIME, time, 20.0, "s"),
            ],
            verdict: Verdict::Pass,
            note: None,
        };
        let listed = |measure: &str| ExpectedFailure {
            solver: "mine".to_owned(),
            case: "hammock / 1 step".to_owned(),
            measure: measure.to_owned(),
            figure: 1.0,
        };
        let list = vec![listed("energy rise"), listed(crate::kit::TIME)];
        // Within its budget now, its energy still failing as listed: an expected failure.
        let mut quick = case(5.0, 7.0);
        apply(&list, "mine", &mut quick);
        quick.judge();
        assert_eq!(quick.verdict, Verdict::ExpectedFail);
        // Stopped at its budget before the rise it is listed for: still only expected.
        let mut stopped = case(25.0, 0.0);
        apply(&list, "mine", &mut stopped);
        stopped.judge();
        assert_eq!(stopped.verdict, Verdict::ExpectedFail);
        // A listed energy rise that passes over a whole run is passes-now, as any listed pass.
        let mut mended = case(5.0, 0.0);
        apply(&list, "mine", &mut mended);
        mended.judge();
        assert_eq!(mended.verdict, Verdict::Fail);
    }
}
