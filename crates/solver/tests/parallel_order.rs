//! The parallel and colored constraint orders (`ConstraintOrder::Parallel`, `Colored`) and
//! threads.
//!
//! Both orders change only the order of the stretch-limit corrections (self-collision is the
//! faithful pass in every order); these tests show they keep the model's constraint and settle
//! where the course's order settles, and that thread counts never change results.

use cloth_mesh::{ClothMesh, ClothState};
use cloth_solver::{ConstraintOrder, Solver, StepParams, Verlet, advance_frame, max_stretch_ratio};

/// Four simulated seconds: the `pinned4` cloth has fallen, swung and settled into its hanging
/// shape (the drag of 5.4 1/s damps motion by e^-21 in that time).
const SETTLE_FRAMES: usize = 360;

/// Runs `frames` frames, then one more step by step, returning the state and the largest
/// `length / rest` seen after any step of that last frame.
fn settle(mesh: &ClothMesh, mut solver: Verlet, frames: usize) -> (ClothState, f64) {
    let params = StepParams::default();
    let mut state = ClothState::new(mesh);
    for _ in 0..frames {
        advance_frame(&mut solver, mesh, &[], &params, &mut state).unwrap();
    }
    let mut worst: f64 = 0.0;
    for _ in 0..params.steps_per_frame {
        solver.step(mesh, &[], &params, &mut state).unwrap();
        worst = worst.max(max_stretch_ratio(mesh, &state));
    }
    (state, worst)
}

fn max_distance(a: &ClothState, b: &ClothState) -> f64 {
    a.positions
        .iter()
        .zip(&b.positions)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max)
}

fn parallel() -> Verlet {
    Verlet::new().with_order(ConstraintOrder::Parallel)
}

#[test]
fn thread_count_never_changes_results() {
    // The force sweep splits rows between threads without changing any sum, the parallel
    // order's bands do not depend on the thread count, and self-collision's boxes are
    // independent: the bits must match. 96 x 96 points, so the threaded passes really
    // split the cloth (they take about 4,096 points a task).
    let mesh = ClothMesh::pinned_grid(96).unwrap();
    let frames = 20;
    for order in [
        ConstraintOrder::Faithful,
        ConstraintOrder::Parallel,
        ConstraintOrder::Colored,
    ] {
        let (one, _) = settle(&mesh, Verlet::new().with_order(order), frames);
        // Three threads too: more threads than this machine's two cores, and two pollers.
        for threads in [2, 3] {
            let many = Verlet::new()
                .with_order(order)
                .with_threads(threads)
                .unwrap();
            assert_eq!(many.threads(), threads);
            let (b, _) = settle(&mesh, many, frames);
            assert!(one == b, "{order:?}: one and {threads} threads differ");
        }
    }
}

#[test]
fn parallel_order_keeps_springs_within_the_limit_as_well_as_the_courses_order() {
    // One sweep does not bring every spring back to 1.1 x rest, in either order: a spring
    // corrected early is re-stretched by later corrections of its neighbours. In the hanging
    // `pinned4` cloth the worst springs sit at the pinned corners, where each pin carries a
    // quarter of a 150 kg/m^2 cloth's weight. Those corners lie inside the first and last row
    // blocks, which the parallel order sweeps in the course's spring order; seams (two rows
    // swept after their neighbours) are away from the pins. So the parallel order's worst spring
    // must match the course's to within 1 % of a rest length, the scale on which the two
    // settled states differ (a fraction of a millimetre on 20 mm springs).
    let mesh = ClothMesh::pinned_grid(50).unwrap();
    let (_, faithful) = settle(&mesh, Verlet::new(), SETTLE_FRAMES);
    let (_, banded) = settle(&mesh, parallel(), SETTLE_FRAMES);
    assert!(faithful > 1.0, "the cloth hangs stretched");
    assert!(
        banded <= faithful + 0.01,
        "parallel order: worst ratio {banded}, the course's order {faithful}"
    );
}

#[test]
fn parallel_order_settles_within_a_tenth_of_the_thickness_of_the_faithful_cloth() {
    // Both orders settle to the same balance of springs, gravity and constraints; they differ
    // only in how each step's residual corrections (tens of micrometres, see above) are shared
    // out, and in which way a self-contact wrinkle relaxes. A tenth of the cloth's thickness
    // (0.95 mm, 5 % of the spacing) is invisible at any zoom and far below the 19 mm repulsion
    // distance, while a wrong constraint (a skipped band, a missed pair) moves the hanging
    // cloth by centimetres.
    let mesh = ClothMesh::pinned_grid(50).unwrap();
    let (faithful, _) = settle(&mesh, Verlet::new(), SETTLE_FRAMES);
    let (banded, _) = settle(&mesh, parallel(), SETTLE_FRAMES);
    let d = max_distance(&faithful, &banded);
    assert!(d < mesh.thickness() / 10.0, "largest difference {d} m");
}

fn colored() -> Verlet {
    Verlet::new().with_order(ConstraintOrder::Colored)
}

#[test]
fn colored_order_keeps_springs_within_the_limit_nearly_as_well_as_the_courses_order() {
    // The colored order corrects each direction's springs in two classes, so at a pinned
    // corner the springs of later directions re-stretch those of earlier ones within the same
    // sweep, as the course's order does from spring to spring; only who carries the residual
    // differs. Its worst spring must stay within 1 % of a rest length (0.2 mm) of the course's:
    // the scale on which the two orders share out a step's residual. A sweep that skips
    // springs is far outside it: leaving out one of the twelve classes puts the worst spring
    // at 1.32 x rest.
    let mesh = ClothMesh::pinned_grid(50).unwrap();
    let (_, faithful) = settle(&mesh, Verlet::new(), SETTLE_FRAMES);
    let (_, classes) = settle(&mesh, colored(), SETTLE_FRAMES);
    assert!(faithful > 1.0, "the cloth hangs stretched");
    assert!(
        classes <= faithful + 0.01,
        "colored order: worst ratio {classes}, the course's order {faithful}"
    );
}

#[test]
fn colored_order_settles_within_a_quarter_of_the_thickness_of_the_faithful_cloth() {
    // Both orders settle to the same balance of springs, gravity and constraints, with each
    // step's residual over-stretch (up to 3 % of a rest length at the pins, 0.6 mm, see
    // above) carried by other springs. A quarter of the cloth's thickness (2.4 mm, an eighth of
    // the spacing) is below a character cell of any view and far below the 19 mm repulsion
    // distance, while a wrong constraint moves the hanging cloth by centimetres: leaving out
    // one of the twelve classes moves it by 13 mm.
    let mesh = ClothMesh::pinned_grid(50).unwrap();
    let (faithful, _) = settle(&mesh, Verlet::new(), SETTLE_FRAMES);
    let (classes, _) = settle(&mesh, colored(), SETTLE_FRAMES);
    let d = max_distance(&faithful, &classes);
    assert!(d < mesh.thickness() / 4.0, "largest difference {d} m");
}

#[test]
fn threads_report_a_non_finite_point_as_one_thread_does() {
    // 96 x 96 points: the threaded finiteness check cuts each array into several tasks. A NaN
    // in a pinned point's last position stays there (pinned points keep their last position),
    // so only the check of the last positions sees it; a NaN or an infinity elsewhere spreads
    // to the positions within a step. Wherever it is, both thread counts must name the same
    // first point.
    let mesh = ClothMesh::pinned_grid(96).unwrap();
    let params = StepParams::default();
    let pin = mesh.pinned().iter().rposition(|&p| p).unwrap();
    let poisons: [(usize, bool, f64); 3] = [
        (pin, false, f64::NAN),
        (mesh.len() - 10, true, f64::INFINITY),
        (50 * 96 + 7, false, f64::NAN),
    ];
    for (point, in_positions, value) in poisons {
        let report = |mut solver: Verlet| {
            let mut state = ClothState::new(&mesh);
            advance_frame(&mut solver, &mesh, &[], &params, &mut state).unwrap();
            let target = if in_positions {
                &mut state.positions
            } else {
                &mut state.last
            };
            target[point].y = value;
            solver.step(&mesh, &[], &params, &mut state).unwrap_err()
        };
        let one = report(Verlet::new());
        let two = report(Verlet::new().with_threads(2).unwrap());
        let cloth_solver::SolveError::NonFinite { point: first, .. } = one else {
            panic!("one thread: {one}");
        };
        assert!(
            first <= point,
            "{point}: the first non-finite point is {first}"
        );
        assert_eq!(one.to_string(), two.to_string(), "{point}");
    }
}
