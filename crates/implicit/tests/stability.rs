//! Both implicit solvers stay finite and settle on every bundled scene, at every step count,
//! with the stretch limit and self-collision on and off, at stiff springs, and after a swap
//! from Verlet at any moment of a fall.
//!
//! The full matrices are long runs, `#[ignore]`d into the long-test command
//! (`cargo test -p cloth-implicit --release -- --ignored`); the default suite keeps the cases
//! that once failed.

mod common;

use cloth_implicit::{FastImplicit, ImplicitEuler, retime_friction, retime_velocity};
use cloth_mesh::ClothState;
use cloth_scene::{BUNDLED, Scene};
use cloth_solver::{Solver, StepParams, Verlet, advance_frame, kinetic_energy};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Seconds of simulated time after which a cloth must have settled.
const SETTLE_SECONDS: f64 = 4.0;

/// The settled bound on the root-mean-square point speed, m/s.
///
/// Why: the drag of the course's damping (c = 5.4 1/s) takes any motion down by
/// e^(-c t) = 4e-10 in the 4 s allowed, from at most the terminal fall speed g / c = 1.8 m/s;
/// what can remain is the slow creep of a cloth still sliding into its rest shape (a drape over
/// the sphere), a few mm/s at most. A cloth that swings, jitters or has exploded moves at tens
/// of cm/s to km/s. 1 cm/s separates the two. Where the model itself keeps a scene moving
/// longer, the matrices hold the implicit solvers to the course's method, see
/// [`reference_speed`].
const SETTLED_RMS_SPEED: f64 = 1e-2;

/// The windows, in frames at 90 frames per second (0.5 s and 0.3 s), over which a cloth
/// resting on a collision object is measured; see [`settle_speed`].
const WINDOWS: [usize; 2] = [45, 27];

/// The root-mean-square point speed, m/s, averaged over the last `frames` frames of `history`
/// (the cloth's positions at the end of each frame).
fn window_speed(history: &[Vec<cloth_mesh::Vec3>], frames: usize, fps: f64) -> f64 {
    let (Some(now), Some(then)) = (history.last(), history.len().checked_sub(frames + 1)) else {
        return f64::INFINITY;
    };
    let then = &history[then];
    let sum: f64 = now
        .iter()
        .zip(then)
        .map(|(a, b)| (a - b).norm_squared())
        .sum();
    (sum / now.len() as f64).sqrt() * fps / frames as f64
}

/// How fast a cloth still moves, as a root-mean-square point speed, m/s, at the end of a frame.
///
/// A cloth with no collision object is measured by its kinetic energy (the last step's
/// velocities), as the speed that energy gives its mass. A cloth resting on a collision
/// object is measured by its displacement over the last 0.5 s and over the last 0.3 s
/// instead, the larger of the two: the course's collision model puts a point that crossed a
/// surface back [`cloth_mesh::SURFACE_OFFSET`] (0.1 mm) outside it, from where it falls freely
/// through the offset again, so a resting point's step velocity swings up to
/// `sqrt(2 g offset)` = 4.4 cm/s (Verlet's cloth at rest on the plane shows several cm/s)
/// while the point never leaves a 0.1 mm band, which moves it by at most 0.2 mm/s over 0.5 s.
/// A motion that returned to the same place after both windows would have a period dividing
/// 0.1 s, and at 1 cm/s an amplitude under 0.2 mm.
///
/// Runs `scene` for [`SETTLE_SECONDS`] with `solver` and `params` and returns that speed at
/// the end of each of the last `span` frames, the last one last; an error names the frame if a
/// frame fails.
fn speeds(
    scene: &Scene,
    solver: &mut dyn Solver,
    params: &StepParams,
    span: usize,
) -> Result<Vec<f64>, String> {
    let mut state = ClothState::new(&scene.mesh);
    let frames = (SETTLE_SECONDS * params.frames_per_sec).round() as usize;
    let mass = scene.mesh.point_mass(params.density);
    let mut history = Vec::new();
    let mut speeds = Vec::with_capacity(span);
    for f in 1..=frames {
        advance_frame(solver, &scene.mesh, &scene.colliders, params, &mut state)
            .map_err(|e| format!("frame {f}: {e}"))?;
        if frames - f >= span {
            if frames - f <= span + WINDOWS[0] && !scene.colliders.is_empty() {
                history.push(state.positions.clone());
            }
            continue;
        }
        speeds.push(if scene.colliders.is_empty() {
            let ke = kinetic_energy(&state, mass, params.dt());
            (2.0 * ke / (mass * scene.mesh.len() as f64)).sqrt()
        } else {
            history.push(state.positions.clone());
            WINDOWS
                .iter()
                .map(|&w| window_speed(&history, w, params.frames_per_sec))
                .fold(0.0, f64::max)
        });
    }
    Ok(speeds)
}

/// How fast the cloth still moves at the end of [`SETTLE_SECONDS`] (see [`speeds`]).
fn settle_speed(
    scene: &Scene,
    solver: &mut dyn Solver,
    params: &StepParams,
) -> Result<f64, String> {
    let speeds = speeds(scene, solver, params, 1)?;
    Ok(speeds.last().copied().unwrap_or(f64::INFINITY))
}

/// [`settle_speed`] held to `bound`, m/s: an error naming the frame that failed or the speed
/// the cloth still had.
fn settles(
    scene: &Scene,
    solver: &mut dyn Solver,
    params: &StepParams,
    bound: f64,
) -> Result<(), String> {
    let speed = settle_speed(scene, solver, params)?;
    if speed <= bound {
        Ok(())
    } else {
        Err(format!(
            "rms speed {speed:.3e} m/s after {SETTLE_SECONDS} s, settled is below {bound:.3e} m/s"
        ))
    }
}

/// The frames (1 s at 90 frames per second) before the end of a reference run over which the
/// model's speed is taken: see [`reference_speed`].
const REFERENCE_SPAN: usize = 90;

/// The fewest Verlet steps per frame that keep a cloth of stiffness `ks`, N/m, stable: 200 at
/// 1e6 N/m (the course's cloth at 90 frames per second), and in proportion to `sqrt(ks)` below
/// that, since an explicit step's stable size goes as `sqrt(m / k)`; never fewer than the
/// scene's own.
fn stable_verlet_steps(scene: &Scene, ks: f64) -> u32 {
    let steps = (200.0 * (ks / 1e6).sqrt()).ceil() as u32;
    steps.max(scene.params.steps_per_frame)
}

/// The bound a case of `scene` with `params`' switches and stiffness is held to, m/s:
/// [`SETTLED_RMS_SPEED`], or the fastest the course's own method still moves during the last
/// second of [`SETTLE_SECONDS`], measured the same way, where that is higher. The method is
/// Verlet with the same switches at the scene's steps per frame, or at the fewest that keep it
/// stable at `params.ks` ([`stable_verlet_steps`]); at more steps than the scene's own its
/// per-step damping and friction are retimed to keep the rates the implicit solvers use (the
/// damping as `1 - e^(-c h)` with the drag rate `c`, the friction by [`retime_friction`], one
/// step of its drag), so the reference is the same physical cloth: with the course's per-step
/// damping applied 200 times a frame, a cloth at 1e6 N/m falls at 27 cm/s and is still falling
/// onto the plane after 3.9 s.
///
/// Why: the reference stands for the model. A scene the model itself has not brought to rest
/// by then cannot be asked to be stiller under another integrator. selfCollision is such a
/// scene: its cloth lands flat and slides into folds for seconds (Verlet's still moves at
/// 2-3 cm/s after 4 s with self-collision off, and falls below 1 cm/s only after about 7 s).
/// Self-collision keeps others moving: the course's correction pushes every pair of points
/// nearer than twice the thickness apart along their join, a step at a time, so cloth layers
/// that touch keep pushing each other: their points jitter in place at several cm/s (the
/// folds of pinned2's cloth, hanging 3.2 times stretched with the limit off, measured by the
/// last step's kinetic energy) or crawl at one to a few cm/s (selfCollision's stacked folds,
/// the drape over the sphere with the limit off).
///
/// Why the last second and not its last frame: such motion comes in bursts, a fold or an edge
/// slipping at once and stopping again (the model's drape over the sphere moves at 0.2-1.1
/// cm/s by turns between 3 s and 8 s, selfCollision at 0.7-4.2 cm/s), and which burst falls on
/// the last frame depends on the integrator's rounding as much as on its physics. A case that
/// moves no faster than the model does at some moment of the second before has come to rest
/// as far as the model has.
/// Where the reference stays below [`SETTLED_RMS_SPEED`] the absolute bound holds.
fn reference_speed(scene: &Scene, params: &StepParams) -> f64 {
    let mut reference = StepParams {
        steps_per_frame: stable_verlet_steps(scene, params.ks),
        ..*params
    };
    let mut scene = scene.clone();
    if reference.steps_per_frame != scene.params.steps_per_frame {
        // The per-step damping that keeps the drag rate at the new step: `1 - e^(-c h)`.
        reference.damping = 100.0 * -(-params.drag_rate() * reference.dt()).exp_m1();
        let colliders = std::mem::take(&mut scene.colliders);
        retime_friction(&colliders, &reference, &mut scene.colliders);
    }
    let speeds = speeds(&scene, &mut Verlet::new(), &reference, REFERENCE_SPAN)
        .unwrap_or_else(|e| panic!("the Verlet reference: {e}"));
    speeds.into_iter().fold(SETTLED_RMS_SPEED, f64::max)
}

/// [`settles`] to [`SETTLED_RMS_SPEED`], panicking with the case's name on failure.
fn finite_and_settles(name: &str, scene: &Scene, solver: &mut dyn Solver, params: &StepParams) {
    if let Err(e) = settles(scene, solver, params, SETTLED_RMS_SPEED) {
        panic!("{name}: {e}");
    }
}

/// One case of a matrix: its name, scene, solver and parameters.
struct Case {
    name: String,
    scene_name: &'static str,
    scene: Scene,
    build: fn() -> Box<dyn Solver>,
    params: StepParams,
}

/// `f(0)`, ..., `f(n - 1)`, computed on two threads, in order.
fn on_two_threads<T: Send>(n: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let results = Mutex::new(Vec::with_capacity(n));
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    if i >= n {
                        break;
                    }
                    let result = f(i);
                    results
                        .lock()
                        .unwrap_or_else(std::sync::PoisonError::into_inner)
                        .push((i, result));
                }
            });
        }
    });
    let mut results = results
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    results.sort_by_key(|&(i, _)| i);
    results.into_iter().map(|(_, result)| result).collect()
}

/// Runs every case on two threads (after the Verlet references they need, each once) and
/// panics at the end with the list of every failing case, so that one run shows all of a
/// matrix's failures.
fn run_all(cases: &[Case]) {
    let key = |c: &Case| {
        (
            c.scene_name,
            c.params.stretch_limit,
            c.params.self_collision,
            c.params.ks.to_bits(),
        )
    };
    let mut references: Vec<&Case> = Vec::new();
    for case in cases {
        if !references.iter().any(|r| key(r) == key(case)) {
            references.push(case);
        }
    }
    let reference_bounds = on_two_threads(references.len(), |i| {
        let case = references[i];
        let bound = reference_speed(&case.scene, &case.params);
        eprintln!(
            "{} / Verlet reference / ks {} / limit {} / self-collision {}: bound {bound:.3e} m/s",
            case.scene_name, case.params.ks, case.params.stretch_limit, case.params.self_collision
        );
        bound
    });
    let outcomes = on_two_threads(cases.len(), |i| {
        let case = &cases[i];
        let r = references.iter().position(|r| key(r) == key(case));
        let bound = reference_bounds[r.expect("every case's reference was run")];
        let started = Instant::now();
        let outcome = settles(&case.scene, (case.build)().as_mut(), &case.params, bound);
        let seconds = started.elapsed().as_secs_f64();
        let verdict = match &outcome {
            Ok(()) => "ok".to_owned(),
            Err(e) => format!("FAILED: {e}"),
        };
        eprintln!("{}: {verdict} ({seconds:.1} s)", case.name);
        outcome.err().map(|e| format!("{}: {e}", case.name))
    });
    let mut failures: Vec<String> = outcomes.into_iter().flatten().collect();
    failures.sort();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// A solver's name and constructor.
type Build = (&'static str, fn() -> Box<dyn Solver>);

fn solvers() -> [Build; 2] {
    [
        ("fast-implicit", || Box::new(FastImplicit::new())),
        ("implicit", || Box::new(ImplicitEuler::new())),
    ]
}

fn load(name: &str) -> Scene {
    cloth_scene::load(name, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Every bundled scene x `steps` x the named solvers x limit on/off x self-collision on/off.
fn every_scene_at(steps: &[u32], solver_names: &[&str]) {
    let mut cases = Vec::new();
    for b in BUNDLED {
        let scene = load(b.name);
        for &steps_per_frame in steps {
            for stretch_limit in [true, false] {
                for self_collision in [true, false] {
                    let params = StepParams {
                        steps_per_frame,
                        stretch_limit,
                        self_collision,
                        ..scene.params
                    };
                    for (solver_name, build) in solvers() {
                        if !solver_names.contains(&solver_name) {
                            continue;
                        }
                        cases.push(Case {
                            name: format!(
                                "{} / {solver_name} / {steps_per_frame} steps per frame / limit \
                                 {stretch_limit} / self-collision {self_collision}",
                                b.name
                            ),
                            scene_name: b.name,
                            scene: scene.clone(),
                            build,
                            params,
                        });
                    }
                }
            }
        }
    }
    run_all(&cases);
}

#[test]
fn fast_implicit_settles_pinned4_at_one_and_five_steps_per_frame() {
    // The course's scene at the step counts where the multiplier ascent the limit once used
    // diverged (frames 122 and 39).
    let scene = load("pinned4");
    for steps_per_frame in [1, 5] {
        for self_collision in [true, false] {
            let params = StepParams {
                steps_per_frame,
                self_collision,
                ..scene.params
            };
            finite_and_settles(
                &format!("pinned4 / {steps_per_frame} steps / self-collision {self_collision}"),
                &scene,
                &mut FastImplicit::new(),
                &params,
            );
        }
    }
}

#[test]
#[ignore = "long: 4 s of pinned2 at 5 steps per frame with the limit (release: about 4 minutes)"]
fn implicit_settles_pinned2_at_five_steps_per_frame_with_the_limit_and_self_collision() {
    // The stretch limit's tolerance is per frame (divided by the steps per frame): springs
    // that each step leaves anywhere within a per-step tolerance would jitter five times
    // faster here than at one step per frame, above the settled bound.
    let scene = load("pinned2");
    let params = StepParams {
        steps_per_frame: 5,
        stretch_limit: true,
        self_collision: true,
        ..scene.params
    };
    finite_and_settles(
        "pinned2 / implicit / 5 steps per frame / limit and self-collision on",
        &scene,
        &mut ImplicitEuler::new(),
        &params,
    );
}

#[test]
fn fast_implicit_settles_the_hammock_whose_width_hangs_at_the_stretch_limit() {
    // The hammock's 63 springs across its width all bind at rest: the long taut chain whose
    // limit multipliers converge too slowly at the moving cloth's limit weight, leaving a
    // jitter in the step velocity unless the weight rises once the cloth is still (see the
    // fast_implicit module doc). The settled bound is the matrices' own.
    let scene = load("hammock");
    let params = StepParams {
        steps_per_frame: 1,
        ..scene.params
    };
    assert!(params.stretch_limit);
    finite_and_settles(
        "hammock / 1 step",
        &scene,
        &mut FastImplicit::new(),
        &params,
    );
}

#[test]
fn fast_implicit_holds_pinned4_at_100_x_100_points_at_one_step_per_frame() {
    // pinned4's settings on a 100 x 100 grid (pins at the corners, the thickness scaled with
    // the spacing), through the fall, the catch on the stretch limit (about frame 25) and the
    // rebound. Its corner springs hold more tension than the limit's weight times 1.1 rest
    // (see the fast_implicit module doc), the state a fine grid's hanging cloth is in.
    //
    // The bound: backward Euler dissipates. The step minimises the incremental potential, whose
    // value at the start bounds the new kinetic plus potential energy; the drag takes energy
    // out and the limit, a constraint, does no work. From rest with every spring at its rest
    // length, the kinetic energy is then at most the work gravity has done, m g . (x - x0)
    // summed over the points, at every frame, with no allowance: the first step from rest
    // already gives only 1 / (2 (1 + c h)) = 0.47 of it (c h = 0.06), and more of that work goes
    // into the springs and the drag as the cloth catches. Self-collision moves a point only
    // when another comes within the 4.7 mm thickness, which the flat fall does not do: moving
    // every one of the 10,000 points (0.015 kg each) by that much within a 1/90 s step would
    // give them 0.5 x 150 kg x (0.0047 x 90 m/s)^2 = 13 J, against hundreds of J of gravity's
    // work by the time the cloth has sagged enough to fold. A cloth that blows up passes the
    // bound within a frame or two of starting to.
    let n: u32 = 100;
    let sets = [
        format!("cloth.num_width_points={n}"),
        format!("cloth.num_height_points={n}"),
        format!("cloth.pinned=[[0,0],[0,{m}],[{m},0],[{m},{m}]]", m = n - 1),
        format!("cloth.thickness={}", 0.0095 * 49.0 / f64::from(n - 1)),
        "simulation.simulation_steps=1".to_owned(),
    ];
    let scene = cloth_scene::load("pinned4", &sets).unwrap_or_else(|e| panic!("{e}"));
    let params = scene.params;
    assert_eq!(params.steps_per_frame, 1);
    let mass = scene.mesh.point_mass(params.density);
    let mut state = ClothState::new(&scene.mesh);
    let start = state.positions.clone();
    let mut solver = FastImplicit::new();
    for f in 1..=45 {
        advance_frame(
            &mut solver,
            &scene.mesh,
            &scene.colliders,
            &params,
            &mut state,
        )
        .unwrap_or_else(|e| panic!("frame {f}: {e}"));
        let work: f64 = state
            .positions
            .iter()
            .zip(&start)
            .map(|(x, x0)| mass * params.gravity.dot(&(x - x0)))
            .sum();
        let ke = kinetic_energy(&state, mass, params.dt());
        assert!(
            ke <= work,
            "frame {f}: kinetic energy {ke:.4e} J above gravity's work {work:.4e} J (largest \
             stretch {:.3e})",
            cloth_solver::max_stretch_ratio(&scene.mesh, &state)
        );
    }
}

#[test]
#[ignore = "long, and not met yet: fast-implicit does not settle on every scene, step count and switch"]
fn fast_implicit_is_finite_and_settles_on_every_scene_step_count_and_switch() {
    every_scene_at(&[1, 2, 5, 10, 30], &["fast-implicit"]);
}

#[test]
#[ignore = "long (release: hours; a case at 10 or 30 steps per frame with the limit on takes \
            three to five minutes), and its outcome on every scene is open"]
fn implicit_is_finite_and_settles_on_every_scene_step_count_and_switch() {
    every_scene_at(&[1, 2, 5, 10, 30], &["implicit"]);
}

/// Every bundled scene x ks in {1e4, 1e5, 1e6} x the named solvers x limit on/off, at one step
/// per frame, each held to the course's Verlet at the same stiffness (see [`reference_speed`]).
fn every_scene_stiff(solver_names: &[&str]) {
    let mut cases = Vec::new();
    for b in BUNDLED {
        let scene = load(b.name);
        for ks in [1e4, 1e5, 1e6] {
            for stretch_limit in [true, false] {
                let params = StepParams {
                    ks,
                    steps_per_frame: 1,
                    stretch_limit,
                    ..scene.params
                };
                for (solver_name, build) in solvers() {
                    if !solver_names.contains(&solver_name) {
                        continue;
                    }
                    cases.push(Case {
                        name: format!(
                            "{} / {solver_name} / ks {ks} / limit {stretch_limit}",
                            b.name
                        ),
                        scene_name: b.name,
                        scene: scene.clone(),
                        build,
                        params,
                    });
                }
            }
        }
    }
    run_all(&cases);
}

#[test]
#[ignore = "long, and not met yet: not every scene settles at ks up to 1e6 and one step per frame"]
fn fast_implicit_is_finite_and_settles_on_every_scene_at_stiff_springs_and_one_step_per_frame() {
    every_scene_stiff(&["fast-implicit"]);
}

#[test]
#[ignore = "long (release: about 10 minutes), and not met yet: the sphere at 1e6 N/m with the \
            limit off does not settle"]
fn implicit_is_finite_and_settles_on_every_scene_at_stiff_springs_and_one_step_per_frame() {
    every_scene_stiff(&["implicit"]);
}

/// Verlet's states of pinned4 at the end of every frame 0..=90, and the largest kinetic energy
/// among them, J.
fn verlet_fall(scene: &Scene) -> (Vec<ClothState>, f64) {
    let mut state = ClothState::new(&scene.mesh);
    let mut verlet = Verlet::new();
    let mass = scene.mesh.point_mass(scene.params.density);
    let mut states = vec![state.clone()];
    let mut most: f64 = 0.0;
    for f in 1..=90 {
        advance_frame(
            &mut verlet,
            &scene.mesh,
            &scene.colliders,
            &scene.params,
            &mut state,
        )
        .unwrap_or_else(|e| panic!("Verlet frame {f}: {e}"));
        most = most.max(kinetic_energy(&state, mass, scene.params.dt()));
        states.push(state.clone());
    }
    (states, most)
}

/// Swaps to `build()` at one step per frame from each of Verlet's states (velocity kept) and
/// runs 90 frames: every frame finite, its kinetic energy never above Verlet's largest.
fn swap_at_every_frame(build: fn() -> Box<dyn Solver>, name: &str) {
    // Backward Euler dissipates: each step lowers kinetic plus potential energy (the step
    // minimises the incremental potential, whose value at the start, x = y, bounds the new
    // energy), so after a swap the cloth can gain kinetic energy only from the potential
    // energy Verlet's fall still had, as Verlet itself does while it falls. The one extra
    // source is the stretch the course's sweep leaves (springs up to ~1.17 rest in the fall),
    // which the implicit limit takes back; its energy is tiny next to the fall's (tens of J)
    // when the limit's pull is bounded, and unbounded only if the solver overshoots, which is
    // the failure this test exists for. Verlet's largest kinetic energy is thus the bound,
    // with no allowance.
    let scene = load("pinned4");
    let (states, verlet_most) = verlet_fall(&scene);
    let params = StepParams {
        steps_per_frame: 1,
        ..scene.params
    };
    let mass = scene.mesh.point_mass(params.density);
    for (f, start) in states.iter().enumerate() {
        let mut state = start.clone();
        retime_velocity(&mut state, scene.params.dt(), params.dt());
        let mut solver = build();
        for g in 1..=90 {
            if let Err(e) = advance_frame(
                solver.as_mut(),
                &scene.mesh,
                &scene.colliders,
                &params,
                &mut state,
            ) {
                panic!("{name} from Verlet's frame {f}: frame {g}: {e}");
            }
            let ke = kinetic_energy(&state, mass, params.dt());
            assert!(
                ke <= verlet_most,
                "{name} from Verlet's frame {f}: frame {g}: kinetic energy {ke:.4e} J above \
                 Verlet's largest {verlet_most:.4e} J"
            );
        }
    }
}

#[test]
#[ignore = "long: 91 swaps x 90 frames (release: about a minute)"]
fn fast_implicit_takes_over_from_verlet_at_any_frame_of_the_fall() {
    swap_at_every_frame(|| Box::new(FastImplicit::new()), "fast-implicit");
}

#[test]
#[ignore = "long: 91 swaps x 90 frames (release: about five minutes)"]
fn implicit_takes_over_from_verlet_at_any_frame_of_the_fall() {
    swap_at_every_frame(|| Box::new(ImplicitEuler::new()), "implicit");
}

#[test]
fn both_take_over_from_verlet_mid_fall_with_the_springs_past_the_limit() {
    // The quick form of the swap tests: frame 27 of the fall, where the course's sweep leaves
    // springs well past 1.1 rest (checked, so the case keeps its point).
    let scene = load("pinned4");
    let (states, verlet_most) = verlet_fall(&scene);
    let start = &states[27];
    let stretch = cloth_solver::max_stretch_ratio(&scene.mesh, start);
    assert!(
        stretch > 1.12,
        "Verlet's frame 27 has its springs at {stretch}"
    );
    let params = StepParams {
        steps_per_frame: 1,
        ..scene.params
    };
    let mass = scene.mesh.point_mass(params.density);
    for (name, build) in solvers() {
        let mut state = start.clone();
        retime_velocity(&mut state, scene.params.dt(), params.dt());
        let mut solver = build();
        for g in 1..=30 {
            advance_frame(
                solver.as_mut(),
                &scene.mesh,
                &scene.colliders,
                &params,
                &mut state,
            )
            .unwrap_or_else(|e| panic!("{name}: frame {g}: {e}"));
            let ke = kinetic_energy(&state, mass, params.dt());
            // The bound's argument is in swap_at_every_frame.
            assert!(
                ke <= verlet_most,
                "{name}: frame {g}: {ke:e} J > {verlet_most:e} J"
            );
        }
    }
}

#[test]
fn implicit_takes_over_near_the_bottom_of_the_fall_without_gaining_energy_the_fall_does_not_give() {
    // Around frame 30 Verlet's pinned4 is caught by its springs at the bottom of its fall and
    // rebounds, its kinetic energy never above 28.5 J from there on, with the course's sweep
    // leaving springs up to ~1.17 rest. Taken over there, the Newton step's first frame turns
    // that excess stretch into motion; after it the cloth swings on the energy it has, so no
    // later frame may have more kinetic energy than that first frame or than Verlet's own
    // cloth from the swap on. A limit whose multipliers leave tension on
    // springs the motion has slackened holds the cloth up and lets it spring back above that.
    let scene = load("pinned4");
    let (states, _) = verlet_fall(&scene);
    let mass = scene.mesh.point_mass(scene.params.density);
    let verlet_ke: Vec<f64> = states
        .iter()
        .map(|s| kinetic_energy(s, mass, scene.params.dt()))
        .collect();
    let params = StepParams {
        steps_per_frame: 1,
        ..scene.params
    };
    for from in [28, 31, 34] {
        let verlet_most = verlet_ke[from..].iter().copied().fold(0.0, f64::max);
        let mut state = states[from].clone();
        retime_velocity(&mut state, scene.params.dt(), params.dt());
        let mut solver = ImplicitEuler::new();
        let mut bound = verlet_most;
        for g in 1..=10 {
            advance_frame(
                &mut solver,
                &scene.mesh,
                &scene.colliders,
                &params,
                &mut state,
            )
            .unwrap_or_else(|e| panic!("from Verlet's frame {from}: frame {g}: {e}"));
            let ke = kinetic_energy(&state, mass, params.dt());
            if g == 1 {
                bound = bound.max(ke);
            }
            assert!(
                ke <= bound,
                "from Verlet's frame {from}: frame {g}: {ke:.4e} J above {bound:.4e} J (the \
                 first frame's or Verlet's most from the swap on, {verlet_most:.4e} J)"
            );
        }
    }
}

#[test]
fn damping_of_100_percent_holds_the_cloth_where_it_is() {
    // An infinite drag: the limit of the damped step is no motion at all (see the solvers'
    // module docs). From a moving state, one step leaves every free point where it was and the
    // velocity zero (self-collision off: it may move points of any state, moving or not).
    let scene = load("pinned4");
    let (states, _) = verlet_fall(&scene);
    let params = StepParams {
        damping: 100.0,
        steps_per_frame: 1,
        self_collision: false,
        ..scene.params
    };
    for (name, build) in solvers() {
        let mut state = states[10].clone();
        build()
            .step(&scene.mesh, &scene.colliders, &params, &mut state)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(state.positions, states[10].positions, "{name}");
        assert_eq!(state.last, state.positions, "{name}");
    }
}
