//! How the implicit solvers are offered by name: their registry entries and options.

use cloth_mesh::ClothMesh;
use cloth_solver::{OptionError, OptionKind, Solver, SolverEntry, SolverOption, SpatialHash};
use serde_json::Value;

use crate::{DEFAULT_ITERATIONS, FastImplicit, ImplicitEuler, NEWTON_TOLERANCE};

impl ImplicitEuler {
    /// The registry entry of backward Euler by Newton's method, `implicit`: one step per frame
    /// (it is stable at any step), option `tolerance` ([`ImplicitEuler::with_tolerance`]).
    pub const ENTRY: SolverEntry = SolverEntry::new(
        "implicit",
        "backward Euler, Newton + line search on faer (stable at large steps)",
        build_implicit,
    )
    .with_steps_per_frame(1)
    .with_memory_estimate(implicit_memory)
    .with_options(&[SolverOption {
        name: "tolerance",
        description: "Newton stops once an iteration moves no point farther than this, metres per frame",
        kind: OptionKind::Number {
            min: 1e-12,
            max: 1e-2,
            default: NEWTON_TOLERANCE,
        },
    }]);
}

impl FastImplicit {
    /// The registry entry of the fast implicit solver, `fast-implicit`: one step
    /// per frame, option `iterations` ([`FastImplicit::with_iterations`]).
    pub const ENTRY: SolverEntry = SolverEntry::new(
        "fast-implicit",
        "L-BFGS over one prefactored matrix (Liu et al. 2017), contact inside the step (fast, stiff)",
        build_fast,
    )
    .with_steps_per_frame(1)
    .with_memory_estimate(fast_memory)
    .with_options(&[SolverOption {
        name: "iterations",
        description: "L-BFGS iterations per step at most (it stops earlier on its tolerance): more is stiffer and closer to implicit",
        kind: OptionKind::Integer {
            min: 1,
            max: 1000,
            default: DEFAULT_ITERATIONS as i64,
        },
    }]);
}

/// [`ImplicitEuler::memory_estimate`] and the self-collision hash it shares with Verlet.
fn implicit_memory(mesh: &ClothMesh, _options: &Value) -> u64 {
    ImplicitEuler::memory_estimate(mesh).saturating_add(SpatialHash::memory_estimate(mesh.len(), 1))
}

/// [`FastImplicit::memory_estimate`] and the self-collision hash it shares with Verlet.
fn fast_memory(mesh: &ClothMesh, _options: &Value) -> u64 {
    FastImplicit::memory_estimate(mesh).saturating_add(SpatialHash::memory_estimate(mesh.len(), 1))
}

fn build_implicit(_mesh: &ClothMesh, options: &Value) -> Result<Box<dyn Solver>, OptionError> {
    let tolerance = ImplicitEuler::ENTRY.number(options, "tolerance")?;
    Ok(Box::new(ImplicitEuler::with_tolerance(tolerance)))
}

fn build_fast(_mesh: &ClothMesh, options: &Value) -> Result<Box<dyn Solver>, OptionError> {
    let iterations = FastImplicit::ENTRY.integer(options, "iterations")?;
    // The entry's range (1 to 1000) fits a u32.
    Ok(Box::new(FastImplicit::with_iterations(iterations as u32)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn mesh() -> ClothMesh {
        ClothMesh::new(&cloth_mesh::GridSpec::default()).unwrap()
    }

    #[test]
    fn fast_implicit_takes_its_iteration_count_from_its_options() {
        assert!(
            FastImplicit::ENTRY
                .build(&mesh(), &json!({"iterations": 3}))
                .is_ok()
        );
        let e = FastImplicit::ENTRY
            .build(&mesh(), &json!({"iterations": 0}))
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "the fast-implicit solver's option iterations is 0, but it must be an integer from 1 to 1000"
        );
        assert_eq!(FastImplicit::with_iterations(7).iterations(), 7);
        assert_eq!(FastImplicit::new().iterations(), DEFAULT_ITERATIONS);
    }

    #[test]
    fn implicit_refuses_a_tolerance_outside_its_range() {
        assert!(
            ImplicitEuler::ENTRY
                .build(&mesh(), &json!({"tolerance": 1e-8}))
                .is_ok()
        );
        let e = ImplicitEuler::ENTRY
            .build(&mesh(), &json!({"tolerance": 1.0}))
            .err()
            .unwrap();
        assert!(e.to_string().contains("tolerance is 1.0"), "{e}");
    }
}
