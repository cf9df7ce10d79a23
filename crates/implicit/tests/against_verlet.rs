//! The implicit solvers checked against the course's Verlet: equilibria, convergence as the
//! step shrinks, settling where Verlet diverges, and stability on a large stiff cloth.

mod common;

use cloth_implicit::{FastImplicit, ImplicitEuler, retime_velocity};
use cloth_mesh::{ClothMesh, ClothState, Vec3};
use cloth_solver::{
    MAX_STRETCH, SolveError, Solver, StepParams, Verlet, advance_frame, max_stretch_ratio,
};
use common::{max_distance, pinned4, settle};

/// The course's parameters without self-collision: self-collision is a post-step correction
/// outside the energy (it would move a rest state by a solver-dependent amount), and the
/// equilibria compared here are those of the spring energy.
fn static_params(ks: f64, stretch_limit: bool) -> StepParams {
    StepParams {
        ks,
        self_collision: false,
        stretch_limit,
        ..StepParams::default()
    }
}

/// Verlet's state after 1 s of the fall and its rest state: run until a whole frame moves no
/// point more than 1e-10 m.
///
/// With the drag of 5.4 1/s, a mode decays by e^(-2.7 / 90) per frame, so a frame's move of
/// 1e-10 m bounds what is left of it by about 1e-10 / (1 - e^(-0.03)) = 3.4e-9 m, far below the
/// 1e-6 m compared.
fn verlet_rest(mesh: &ClothMesh, params: &StepParams) -> (ClothState, ClothState) {
    let mut state = ClothState::new(mesh);
    let mut verlet = Verlet::new();
    for _ in 0..90 {
        advance_frame(&mut verlet, mesh, &[], params, &mut state).expect("Verlet stays finite");
    }
    let at_one_second = state.clone();
    let (frames, moved) = settle(&mut verlet, mesh, params, &mut state, 1e-10, 90 * 40)
        .expect("Verlet stays finite below its ks limit");
    assert!(
        moved <= 1e-10,
        "Verlet still moving {moved:e} m/frame after {frames} frames"
    );
    (at_one_second, state)
}

/// The implicit rest state from `start` (a Verlet state at the course's step): steps of 0.25 s
/// (backward Euler shrinks a mode of angular frequency w by 1 / (1 + c h + w^2 h^2) per step)
/// until a step moves no point more than 1e-11 m, Newton converged to 1e-11 m per step.
///
/// NOTE: the run starts from Verlet's state 1 s into the fall, not from the flat cloth: pinned2's
/// curtain has several rest states (the slack top edge between the pins folds one way or the
/// other) and which one a run reaches depends on its path; backward Euler at 0.25 s steps takes
/// another path than Verlet at 1/2700 s. After 1 s both are in the same basin, so the comparison
/// is between fixed points, which is what this check is about.
///
/// `slack` raises the iterations a step may take (Newton's and the conjugate gradient's) to
/// what a slack edge needs: at a quarter-second step the factor overstates its stiffness
/// about a hundred thousand times, and the default iterations converge it over hours of
/// simulated time rather than in the run.
fn implicit_rest(
    mesh: &ClothMesh,
    params: &StepParams,
    start: &ClothState,
    slack: bool,
) -> ClothState {
    let big = StepParams {
        steps_per_frame: 1,
        frames_per_sec: 4.0,
        ..*params
    };
    let mut state = start.clone();
    retime_velocity(&mut state, params.dt(), big.dt());
    let mut solver = ImplicitEuler::with_tolerance(1e-11);
    if slack {
        solver = solver.with_iterations(50, 200);
    }
    let (steps, moved) = settle(&mut solver, mesh, &big, &mut state, 1e-11, 500)
        .expect("the implicit solver does not fail");
    assert!(
        moved <= 1e-11,
        "implicit still moving {moved:e} m/step after {steps} steps"
    );
    state
}

/// The largest move of Verlet started at rest from `state`, over 2 s.
fn verlet_drift_from(mesh: &ClothMesh, params: &StepParams, state: &ClothState) -> f64 {
    let mut s = ClothState {
        positions: state.positions.clone(),
        last: state.positions.clone(),
    };
    let mut verlet = Verlet::new();
    let mut drift: f64 = 0.0;
    for _ in 0..180 {
        advance_frame(&mut verlet, mesh, &[], params, &mut s).expect("Verlet stays finite");
        drift = drift.max(max_distance(&s.positions, &state.positions));
    }
    drift
}

#[test]
fn without_the_limit_implicit_and_verlet_rest_at_the_same_equilibrium() {
    // Both rest states solve grad E = 0 (Verlet's fixed point has zero net force; backward
    // Euler's has x = y, hence grad E = 0), so they may differ only by how far each run is
    // from that point: ~3e-9 m for Verlet (see verlet_rest) and ~1e-11 m for the implicit run.
    // A bound of 1e-6 m leaves room for nothing else. The implicit rest state is also checked
    // to be Verlet's fixed point: Verlet released from it moves no point by 1e-6 m in 2 s (a
    // state 1e-6 m off along any mode faster than 1 rad/s would move by about that much).
    let mesh = pinned4(50);
    for ks in [1e5, 5000.0] {
        let params = static_params(ks, false);
        let (start, v) = verlet_rest(&mesh, &params);
        let i = implicit_rest(&mesh, &params, &start, false);
        let d = max_distance(&v.positions, &i.positions);
        let drift = verlet_drift_from(&mesh, &params, &i);
        eprintln!(
            "pinned4 ks={ks}: |verlet - implicit| = {d:.3e} m, Verlet's drift from the \
             implicit rest state {drift:.3e} m"
        );
        assert!(drift < 1e-6, "ks={ks}: Verlet drifts {drift:e} m");
        assert!(d < 1e-6, "ks={ks}: rest states differ by {d:e} m");
    }
}

#[test]
fn with_the_limit_rest_states_agree_within_the_limiters_give() {
    // Both rest states minimise E with every spring held near 1.1 rest where the limit binds;
    // they differ only in how exactly each holds it. The implicit one holds a binding spring at
    // 1.1 rest by its multiplier, up to what the multipliers' iteration leaves; Verlet's is the
    // fixed point of one Provot sweep per step, which leaves each binding spring off 1.1 rest
    // by the part of a step's stretch (F dt^2 / m) that the sweep's later corrections undo. A
    // point's offset is the sum of these length errors along the chain of binding springs that
    // ties it to a pin, at most nw + nh - 2 springs on the grid, so
    // |x_verlet - x_implicit| <= (nw + nh - 2) max_binding (|l_v - 1.1 L| + |l_i - 1.1 L|).
    // A binding spring is one the implicit state holds at the limit: within a millionth of its
    // rest length of it, or past it (the multipliers leave it on either side by rounding). The
    // figure is printed next to the bound. pinned2's slack edge is compared by the fixed-point
    // check of the long test above.
    for (name, mesh) in [("pinned4", pinned4(50))] {
        for ks in [1e5, 5000.0] {
            let params = static_params(ks, true);
            let (start, v) = verlet_rest(&mesh, &params);
            let i = implicit_rest(&mesh, &params, &start, true);
            let ratio = max_stretch_ratio(&mesh, &i);
            let len = |st: &ClothState, s: &cloth_mesh::Spring| {
                (st.positions[s.a as usize] - st.positions[s.b as usize]).norm()
            };
            let worst = mesh
                .springs()
                .iter()
                .filter(|s| len(&i, s) >= (MAX_STRETCH - 1e-6) * s.rest)
                .map(|s| {
                    let limit = MAX_STRETCH * s.rest;
                    (len(&v, s) - limit).abs() + (len(&i, s) - limit).abs()
                })
                .fold(0.0, f64::max);
            // Plus how far each run may still be from its own fixed point: 3.4e-9 m for
            // Verlet's (see verlet_rest), 1e-11 m for the implicit one. Where both hold every
            // binding spring at 1.1 rest to rounding, that is all that separates them.
            let bound = (mesh.nw() + mesh.nh() - 2) as f64 * worst + 3.4e-9 + 1e-11;
            let d = max_distance(&v.positions, &i.positions);
            eprintln!(
                "{name} ks={ks}: |verlet - implicit| = {d:.3e} m, bound {bound:.3e} m \
                 (largest binding-length error {worst:.3e} m, implicit stretch ratio \
                 {ratio:.5}, Verlet's {:.5})",
                max_stretch_ratio(&mesh, &v),
            );
            assert!(d <= bound, "{name} ks={ks}: {d:e} m > {bound:e} m");
            // Converged multipliers hold the limit: no spring 0.1 % of its rest length past it.
            assert!(
                ratio < MAX_STRETCH + 1e-3,
                "{name} ks={ks}: stretch ratio {ratio}"
            );
        }
    }
}

/// The largest distance between Verlet's trajectory (the course's step) and the implicit
/// solver's at `steps_per_frame`, at every frame of the first 0.3 s of a perturbed cloth.
fn max_deviation_over_first_0_3_s(steps_per_frame: u32) -> f64 {
    let mesh = pinned4(25);
    // A smooth 5 cm bump, zero at the pinned corners, released from rest.
    let mut start = ClothState::new(&mesh);
    let n = mesh.nw();
    for y in 0..n {
        for x in 0..n {
            let (u, w) = (x as f64 / (n - 1) as f64, y as f64 / (n - 1) as f64);
            let i = mesh.index(x, y);
            let lift = 0.05 * (std::f64::consts::PI * u).sin() * (std::f64::consts::PI * w).sin();
            start.positions[i] += Vec3::new(0.0, lift, 0.0);
            start.last[i] = start.positions[i];
        }
    }
    // ks = 1000: the grid's fastest mode, sqrt(8 ks / m) = 183 rad/s for these 0.24 kg
    // points, is then resolved (w h < 0.35) at every step compared, which is what "small
    // steps" means for an asymptotic rate; stiffer springs need proportionally smaller steps.
    let params = static_params(1000.0, false);
    // The reference is Verlet at 16 x the course's steps per frame, its per-step damping
    // factor (1 - d) taken to the 1/16th power so that its drag stays the course's c: Verlet's
    // own O(c dt) error then sits well below the implicit deviations measured.
    let reference = StepParams {
        steps_per_frame: 16 * params.steps_per_frame,
        damping: 100.0 * (1.0 - (1.0 - params.damping / 100.0).powf(1.0 / 16.0)),
        ..params
    };
    let coarse = StepParams {
        steps_per_frame,
        ..params
    };
    let (mut v, mut i) = (start.clone(), start);
    let mut verlet = Verlet::new();
    let mut implicit = ImplicitEuler::with_tolerance(1e-10);
    let mut worst: f64 = 0.0;
    for _ in 0..27 {
        advance_frame(&mut verlet, &mesh, &[], &reference, &mut v).expect("Verlet is stable");
        advance_frame(&mut implicit, &mesh, &[], &coarse, &mut i).expect("implicit is stable");
        worst = worst.max(max_distance(&v.positions, &i.positions));
    }
    worst
}

#[test]
fn halving_the_step_halves_the_deviation_from_verlet() {
    // Backward Euler is first-order: its global error is C h + O(h^2). The reference, Verlet
    // at 1/43200 s (20 to 80 times smaller than the steps here), has an error of its own that
    // does not shrink with h (first order in c dt through its damping term); the deviation is
    // thus C h + b. With b and the O(h^2) term each a few percent of the smallest deviation,
    // the ratio stays within 0.4..0.6 of a pure 1/2 exactly when the method is first order (a
    // second-order method would give 1/4, a non-converging one 1).
    let d: Vec<f64> = [6, 12, 24]
        .into_iter()
        .map(max_deviation_over_first_0_3_s)
        .collect();
    eprintln!("max deviation at 6, 12, 24 steps per frame: {d:?}");
    for pair in d.windows(2) {
        let ratio = pair[1] / pair[0];
        assert!((0.4..0.6).contains(&ratio), "ratio {ratio} in {d:?}");
    }
}

/// Runs `frames` frames and returns the last frame's largest move, or the error.
fn run_frames(
    solver: &mut dyn Solver,
    mesh: &ClothMesh,
    params: &StepParams,
    frames: usize,
) -> Result<f64, SolveError> {
    let mut state = ClothState::new(mesh);
    let mut moved = f64::INFINITY;
    for _ in 0..frames {
        let before = state.positions.clone();
        advance_frame(solver, mesh, &[], params, &mut state)?;
        moved = max_distance(&before, &state.positions);
    }
    Ok(moved)
}

#[test]
fn one_implicit_step_per_frame_settles_where_verlet_diverges() {
    // pinned4 with the course's parameters at h = 1/90 s, self-collision off: it is a
    // post-step correction outside the energy, and cloth-solver's spatial hash overflows its
    // box index (a debug-build panic) on the astronomically large positions of a diverging
    // Verlet run before they become non-finite.
    // Verlet is stable only for ks < m / (2 h^2) = 243 N/m here, so at 5000 and 1e6 it must
    // blow up (the limit hides stretch blow-ups, not the others: a point goes non-finite or
    // jitters by centimetres a frame). The implicit solver must stay finite and come to rest:
    // after 3 s (16 e-folds of the 5.4 1/s drag from ~1 m/s) a frame moves no point by more
    // than 1 mm, where a cloth still swinging moves it by centimetres.
    let mesh = pinned4(50);
    for ks in [5000.0, 1e6] {
        let params = StepParams {
            ks,
            steps_per_frame: 1,
            self_collision: false,
            ..StepParams::default()
        };
        let verlet = run_frames(&mut Verlet::new(), &mesh, &params, 90);
        eprintln!("ks={ks}: Verlet at one step per frame: {verlet:?}");
        assert!(
            verlet.is_err() || verlet.is_ok_and(|m| m > 1e-2),
            "Verlet at h = 1/90 s should diverge at ks = {ks}"
        );
        let implicit = run_frames(&mut ImplicitEuler::new(), &mesh, &params, 270)
            .expect("the implicit solver stays finite");
        eprintln!("ks={ks}: implicit last-frame move {implicit:.3e} m");
        assert!(implicit < 1e-3, "ks={ks}: still moving {implicit} m/frame");
    }
}

#[test]
fn fast_implicit_is_stable_at_100x100_and_ks_1e5_where_verlet_at_30_substeps_is_not() {
    // On a 100 x 100 cloth a point weighs 0.015 kg, so Verlet at 1/2700 s is stable only for
    // ks < 0.015 / (2 (1/2700)^2) = 5.5e4 N/m: at 1e5 it must diverge within the first second.
    // The fast implicit solver at one step per frame must stay finite and slow down: 3 s of
    // drag (16 e-folds) brings the last frame's move under 1 mm.
    let mesh = pinned4(100);
    // Self-collision off, as in the test above.
    let verlet_params = StepParams {
        ks: 1e5,
        self_collision: false,
        ..StepParams::default()
    };
    let verlet = run_frames(&mut Verlet::new(), &mesh, &verlet_params, 90);
    eprintln!("Verlet, 30 substeps, 100x100, ks=1e5: {verlet:?}");
    assert!(verlet.is_err() || verlet.is_ok_and(|m| m > 1e-2));
    let fast_params = StepParams {
        steps_per_frame: 1,
        ..verlet_params
    };
    let fast = run_frames(&mut FastImplicit::new(), &mesh, &fast_params, 270)
        .expect("the fast implicit solver stays finite");
    eprintln!("fast implicit last-frame move {fast:.3e} m");
    assert!(fast < 1e-3, "still moving {fast} m/frame");
}

#[test]
fn without_the_limit_fast_implicit_holds_verlets_equilibrium() {
    // At a fixed point of the local/global iteration the global step returns its own input,
    // which makes the gradient of E zero: fast-implicit's rest states are the spring energy's
    // equilibria, Verlet's too. Released at rest from Verlet's equilibrium (itself within
    // ~3e-9 m of the exact one, see verlet_rest), it must stay there: a start 1e-6 m off its
    // own fixed point along any mode faster than 1 rad/s would move by about that much in the
    // 2 s run (the drag and the iteration both pull it home), so a drift under 1e-6 m bounds
    // the distance between the two rest states by the 1e-6 m asked of them.
    let mesh = pinned4(50);
    for ks in [1e5, 5000.0] {
        let params = static_params(ks, false);
        let (_, v) = verlet_rest(&mesh, &params);
        let fast_params = StepParams {
            steps_per_frame: 1,
            ..params
        };
        let mut s = ClothState {
            positions: v.positions.clone(),
            last: v.positions.clone(),
        };
        let mut fast = FastImplicit::with_iterations(50);
        let mut drift: f64 = 0.0;
        for _ in 0..180 {
            advance_frame(&mut fast, &mesh, &[], &fast_params, &mut s).expect("finite");
            drift = drift.max(max_distance(&s.positions, &v.positions));
        }
        eprintln!("ks={ks}: fast-implicit's drift from Verlet's rest state {drift:.3e} m");
        assert!(drift < 1e-6, "ks={ks}: drift {drift:e} m");
    }
}

#[test]
fn with_the_limit_the_pinned4_centre_settles_within_5_mm_of_verlets() {
    // The course's pinned4 at its defaults hangs on its stretch limit: most springs from the
    // corners bind. The forms of the limit hold a binding spring at different lengths: the
    // implicit solvers' exact constraint at 1.1 rest once their multipliers converge (both hold
    // it the same way, to within what each step's iterations leave), and Verlet's sweep, which
    // corrects one spring after another so that later corrections stretch earlier springs
    // again, a few tenths of a percent of rest over it at rest (its largest ratio is printed).
    // The centre hangs from a chain of about 35 binding springs from each corner (the
    // 49-spring diagonal less the slack middle), so 0.5 % of a 2 cm spring on each moves it by
    // 35 x 1e-4 = 3.5 mm: the two implicit solvers agree with each other to a fraction of a
    // millimetre and with Verlet to within the 5 mm asked; a limit that gave way (or a
    // solver that had not settled) moves the centre by centimetres.
    let mesh = pinned4(50);
    let params = StepParams {
        self_collision: false,
        ..StepParams::default()
    };
    let (_, v) = verlet_rest(&mesh, &params);
    eprintln!(
        "Verlet's largest stretch ratio at rest {:.5}",
        max_stretch_ratio(&mesh, &v)
    );
    let centre = mesh.index(25, 25);
    let one_step = StepParams {
        steps_per_frame: 1,
        ..params
    };
    let cases: [(&str, Box<dyn Solver>); 2] = [
        ("fast-implicit", Box::new(FastImplicit::new())),
        ("implicit", Box::new(ImplicitEuler::new())),
    ];
    for (name, mut solver) in cases {
        let mut s = ClothState::new(&mesh);
        for _ in 0..450 {
            advance_frame(solver.as_mut(), &mesh, &[], &one_step, &mut s).expect("finite");
        }
        let d = (s.positions[centre] - v.positions[centre]).norm();
        eprintln!("{name}: centre {d:.3e} m from Verlet's");
        assert!(d < 5e-3, "{name}: centre {d} m from Verlet's");
    }
}
