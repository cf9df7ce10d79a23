//! How the Verlet solver is offered by name: its registry entry and options.

use cloth_mesh::ClothMesh;
use serde_json::Value;

use crate::{ConstraintOrder, OptionError, OptionKind, Solver, SolverEntry, SolverOption, Verlet};

/// The constraint orders by option value, in [`ConstraintOrder`]'s order.
const ORDERS: [(&str, ConstraintOrder); 3] = [
    ("faithful", ConstraintOrder::Faithful),
    ("parallel", ConstraintOrder::Parallel),
    ("colored", ConstraintOrder::Colored),
];

const OPTIONS: &[SolverOption] = &[
    SolverOption {
        name: "threads",
        description: "worker threads of the force sweep and self-collision (results do not \
                      depend on it)",
        kind: OptionKind::Integer {
            min: 1,
            max: 256,
            default: 1,
        },
    },
    SolverOption {
        name: "order",
        description: "order of the stretch-limit and self-collision passes: faithful (the \
                      course's), parallel (row bands) or colored (fastest on big cloths)",
        kind: OptionKind::Choice {
            choices: &["faithful", "parallel", "colored"],
            default: "faithful",
        },
    },
];

impl Verlet {
    /// The registry entry of the faithful explicit Verlet solver, `verlet`: 30 steps per frame
    /// (the course's), options `threads` ([`Verlet::with_threads`]) and `order`
    /// ([`Verlet::with_order`]).
    pub const ENTRY: SolverEntry = SolverEntry::new(
        "verlet",
        "explicit damped Verlet, the course's reference (faithful)",
        build,
    )
    .with_steps_per_frame(crate::REFERENCE_STEPS_PER_FRAME)
    .with_options(OPTIONS)
    .with_memory_estimate(memory_estimate)
    .explicit();
}

/// The options' order, or the faithful one when they do not name one.
fn order_of(options: &Value) -> ConstraintOrder {
    let name = Verlet::ENTRY.choice(options, "order").unwrap_or("faithful");
    ORDERS
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(ConstraintOrder::Faithful, |&(_, o)| o)
}

/// [`Verlet::memory_estimate`] with the threads and order the options ask for.
fn memory_estimate(mesh: &ClothMesh, options: &Value) -> u64 {
    let threads = Verlet::ENTRY.integer(options, "threads").unwrap_or(1);
    Verlet::memory_estimate(mesh, threads.max(1) as usize, order_of(options))
}

fn build(_mesh: &ClothMesh, options: &Value) -> Result<Box<dyn Solver>, OptionError> {
    let entry = Verlet::ENTRY;
    let threads = entry.integer(options, "threads")?;
    entry.choice(options, "order")?;
    let order = order_of(options);
    let verlet = Verlet::new()
        .with_threads(threads as usize)
        .map_err(|e| OptionError::Failed {
            solver: entry.name(),
            reason: e.to_string(),
        })?
        .with_order(order);
    Ok(Box::new(verlet))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn every_order_option_names_a_constraint_order() {
        let OptionKind::Choice { choices, .. } = OPTIONS[1].kind else {
            panic!("order is a choice");
        };
        assert_eq!(choices, ORDERS.map(|(n, _)| n));
    }

    #[test]
    fn the_entry_builds_the_solver_it_is_asked_for() {
        let mesh = cloth_mesh::ClothMesh::new(&cloth_mesh::GridSpec::default()).unwrap();
        let s = Verlet::ENTRY
            .build(&mesh, &json!({"threads": 2, "order": "colored"}))
            .unwrap();
        assert_eq!(s.name(), "verlet");
        let e = Verlet::ENTRY
            .build(&mesh, &json!({"iterations": 10}))
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "the verlet solver has no option \"iterations\"; its options: threads, order"
        );
    }
}
