//! Analytic equilibria: a hanging spring and a hanging chain.

mod common;

use cloth_implicit::{FastImplicit, ImplicitEuler};
use cloth_mesh::{ClothMesh, ClothState, GridSpec};
use cloth_solver::{Solver, StepParams};
use common::settle;

/// A horizontal `2 x rows` cloth pinned at both ends of row 0, with only structural springs:
/// two chains along z joined by rungs. Both chains hang identically below their pins, so the
/// rungs stay at their rest length (1 m) and carry nothing: each column is a free chain.
fn ladder(rows: usize) -> ClothMesh {
    ClothMesh::new(&GridSpec {
        num_width_points: 2,
        num_height_points: rows,
        pinned: vec![(0, 0), (1, 0)],
        ..GridSpec::default()
    })
    .unwrap()
}

/// Structural springs only, no limit, no self-collision; steps of 0.25 s so the hanging
/// pendulum comes to rest in a few dozen steps (backward Euler shrinks a mode of angular
/// frequency w by 1 / (1 + c h + w^2 h^2) per step: at most ~0.5 for these chains).
fn params(ks: f64) -> StepParams {
    StepParams {
        ks,
        shearing: false,
        bending: false,
        stretch_limit: false,
        self_collision: false,
        steps_per_frame: 1,
        frames_per_sec: 4.0,
        ..StepParams::default()
    }
}

fn rest_state(solver: &mut dyn Solver, mesh: &ClothMesh, params: &StepParams) -> ClothState {
    let mut state = ClothState::new(mesh);
    let (steps, moved) = settle(solver, mesh, params, &mut state, 1e-12, 2000).unwrap();
    assert!(
        moved <= 1e-12,
        "still moving {moved:e} m after {steps} steps"
    );
    state
}

/// Checks that row `r` of each column hangs at `1 - sum_{j=1..r} (L + (rows - j) m g / k)`,
/// straight below its pin: spring `j` carries the `rows - j` points below it.
fn assert_hangs_as_a_chain(mesh: &ClothMesh, state: &ClothState, p: &StepParams, tol: f64) {
    let rows = mesh.nh();
    let rest = 1.0 / (rows - 1) as f64;
    let weight = mesh.point_mass(p.density) * p.gravity.norm();
    for x in 0..2 {
        let mut y = 1.0;
        for r in 1..rows {
            y -= rest + (rows - r) as f64 * weight / p.ks;
            let q = state.positions[mesh.index(x, r)];
            let err = ((q.x - x as f64).powi(2) + (q.y - y).powi(2) + q.z.powi(2)).sqrt();
            assert!(err < tol, "column {x} row {r}: off by {err:e} m ({q:?})");
        }
    }
}

#[test]
fn a_hanging_spring_stretches_by_m_g_over_k() {
    // One spring per column, a 37.5 kg point below it: stretch m g / k = 367.5 / 1e5 m.
    // The rest state is the exact root of grad E = 0 up to the settle criterion (1e-12 m per
    // step) and rounding of 1 m coordinates (1e-16 m times the condition number
    // k / (m g / L) ~ 300). The stretch itself is checked to 1e-9 m; the position to 1e-8 m,
    // because the fast solver's ten local/global iterations close in on the pendulum's rest
    // angle (the soft direction) only slowly, leaving ~1e-9 m when a step moves < 1e-12 m.
    let mesh = ladder(2);
    let p = params(1e5);
    for solver in [
        &mut ImplicitEuler::with_tolerance(1e-12) as &mut dyn Solver,
        &mut FastImplicit::new(),
    ] {
        let state = rest_state(solver, &mesh, &p);
        let stretch = 1.0 - state.positions[mesh.index(0, 1)].y - 1.0;
        let expected = mesh.point_mass(p.density) * 9.8 / p.ks;
        assert!(
            (stretch - expected).abs() < 1e-9,
            "{}: stretch {stretch} vs m g / k = {expected}",
            solver.name()
        );
        assert_hangs_as_a_chain(&mesh, &state, &p, 1e-8);
    }
}

#[test]
fn a_hanging_chain_stretches_each_link_by_the_weight_below_it() {
    // Ten points per column (nine links of 1/9 m, 7.5 kg points). Same argument as the single
    // spring; the chain's condition number is ~N^2 larger, so allow 1e-8 m.
    let mesh = ladder(10);
    let p = params(1e5);
    for solver in [
        &mut ImplicitEuler::with_tolerance(1e-12) as &mut dyn Solver,
        &mut FastImplicit::new(),
    ] {
        let state = rest_state(solver, &mesh, &p);
        assert_hangs_as_a_chain(&mesh, &state, &p, 1e-8);
    }
}
