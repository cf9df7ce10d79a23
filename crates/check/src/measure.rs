//! One run of a case with its figures taken frame by frame, and one swap case.

use std::sync::Arc;
use std::time::Instant;

use cloth_mesh::{ClothMesh, ClothState, StepParams, Vec3};
use cloth_scene::Scene;
use cloth_solver::{SolverEntry, Verlet, max_stretch_ratio};
use serde_json::{Value, json};

use crate::stepper::Stepper;
use crate::{CheckError, energy};

/// Simulated seconds of a run: the cloths of the bundled scenes have fallen, caught and (in the
/// model) come to rest or to a slow creep by then.
pub const RUN_SECONDS: f64 = 4.0;
/// The time from which the sum of rises of `H` is taken, s: the fall is over.
pub const RISE_FROM_SECONDS: f64 = 2.0;
/// The time from which the largest stretch is taken, s: the first catch is over.
pub const STRETCH_FROM_SECONDS: f64 = 1.0;
/// The span at the end of a run over which a cloth in contact is held to its mean speed, s.
pub const SETTLE_SPAN_SECONDS: f64 = 1.0;

/// The figures of one run, taken at the end of every frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RunFigures {
    /// Frames completed.
    pub frames: usize,
    /// Frames the run was to have.
    pub planned: usize,
    /// The solver's error, when a frame failed.
    pub error: Option<String>,
    /// Whether the run was stopped at its deadline.
    pub stopped: bool,
    /// Pinned points that ever left their start position by any bit.
    pub pins_moved: usize,
    /// `max H - H(0)` over the frames run, J.
    pub energy_peak: f64,
    /// The sum of the rises of `H` between frames after [`RISE_FROM_SECONDS`], J.
    pub energy_rise: f64,
    /// The largest spring length over rest after [`STRETCH_FROM_SECONDS`].
    pub max_stretch: f64,
    /// The settling speed, m/s (see [`settle_speed`] for which).
    pub settle: f64,
    /// The scene's energy scale `E = M |g| L`, J.
    pub energy_scale: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl RunFigures {
    /// Whether the run went to its end.
    pub(crate) fn complete(&self) -> bool {
        self.frames == self.planned && self.error.is_none()
    }
}

/// Frames in `seconds` at `params`' frame rate.
pub(crate) fn frames_in(seconds: f64, params: &StepParams) -> usize {
    (seconds * params.frames_per_sec).round() as usize
}

/// The root-mean-square point speed from the step velocity, m/s: the speed the kinetic energy
/// gives the cloth's mass.
fn step_speed(mesh: &ClothMesh, state: &ClothState, params: &StepParams) -> f64 {
    let mass = mesh.point_mass(params.density) * mesh.len() as f64;
    (2.0 * energy::kinetic(mesh, state, params) / mass).sqrt()
}

/// The root-mean-square point speed over the last frame, m/s: each point's displacement since
/// the previous frame over the frame's duration.
fn frame_speed(now: &[Vec3], before: &[Vec3], params: &StepParams) -> f64 {
    let sum: f64 = now
        .iter()
        .zip(before)
        .map(|(a, b)| (a - b).norm_squared())
        .sum();
    (sum / now.len() as f64).sqrt() * params.frames_per_sec
}

/// Runs `entry`'s solver on the scene's cloth from rest for [`RUN_SECONDS`] with `params`,
/// taking the figures of every frame; stops at the first failed frame, or at `deadline`.
pub(crate) fn run(
    scene: &Arc<Scene>,
    params: StepParams,
    entry: &SolverEntry,
    options: &Value,
    deadline: Option<Instant>,
) -> Result<RunFigures, CheckError> {
    let started = Instant::now();
    let (mesh, colliders) = (&scene.mesh, &scene.colliders);
    let mut stepper = Stepper::new(scene, params, entry, options)?;
    let planned = frames_in(RUN_SECONDS, &params);
    let rise_from = frames_in(RISE_FROM_SECONDS, &params);
    let stretch_from = frames_in(STRETCH_FROM_SECONDS, &params);
    let settle_from = planned.saturating_sub(frames_in(SETTLE_SPAN_SECONDS, &params));
    let contact = !colliders.is_empty();
    let start = stepper.state().positions.clone();
    let pinned: Vec<usize> = (mesh.pinned().iter().enumerate())
        .filter(|(_, p)| **p)
        .map(|(i, _)| i)
        .collect();
    let mut moved = vec![false; pinned.len()];
    let h0 = energy::total(mesh, stepper.state(), &params);
    let mut figures = RunFigures {
        frames: 0,
        planned,
        error: None,
        stopped: false,
        pins_moved: 0,
        energy_peak: 0.0,
        energy_rise: 0.0,
        max_stretch: 0.0,
        settle: 0.0,
        energy_scale: energy::scale(mesh, &params),
        seconds: 0.0,
    };
    let mut previous_h = h0;
    let mut previous = start.clone();
    let mut speed_sum = 0.0;
    for frame in 1..=planned {
        if deadline.is_some_and(|d| Instant::now() > d) {
            figures.stopped = true;
            break;
        }
        if let Err(e) = stepper.frame() {
            figures.error = Some(format!("frame {frame}: {e}"));
            break;
        }
        let state = stepper.state();
        if let Some(i) = state.first_non_finite() {
            figures.error = Some(format!("frame {frame}: point {i} is not finite"));
            break;
        }
        figures.frames = frame;
        for (m, &i) in moved.iter_mut().zip(&pinned) {
            let same = (state.positions[i].iter().zip(start[i].iter()))
                .all(|(a, b)| a.to_bits() == b.to_bits());
            *m |= !same;
        }
        let h = energy::total(mesh, state, &params);
        figures.energy_peak = figures.energy_peak.max(h - h0);
        if frame > rise_from {
            figures.energy_rise += (h - previous_h).max(0.0);
        }
        previous_h = h;
        if frame >= stretch_from {
            figures.max_stretch = figures.max_stretch.max(max_stretch_ratio(mesh, state));
        }
        if contact && frame > settle_from {
            speed_sum += frame_speed(&state.positions, &previous, &params);
        }
        if contact {
            previous.clone_from(&state.positions);
        }
    }
    figures.pins_moved = moved.iter().filter(|m| **m).count();
    figures.settle = if contact {
        speed_sum / (planned - settle_from).max(1) as f64
    } else {
        step_speed(mesh, stepper.state(), stepper.params())
    };
    figures.seconds = started.elapsed().as_secs_f64();
    Ok(figures)
}

/// The kinetic energies of a swap case, J, each after one frame and compared with the frame
/// the solver it replaces would have given.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SwapFigures {
    /// Verlet's frame `at + 1`.
    pub verlet: f64,
    /// The solver's first frame, taking over from Verlet's frame `at`.
    pub to: f64,
    /// The solver's second frame.
    pub solver: f64,
    /// Verlet's frame taking back over from the solver's first.
    pub back: f64,
    /// The solver's frame after its steps per frame are edited, from its first.
    pub edit: f64,
    /// The steps per frame of the edit.
    pub edit_steps: u32,
    /// The energy of Verlet's motion at frame `at`, where the solver takes over: kinetic plus
    /// the springs' elastic energy, J.
    pub motion_to: f64,
    /// The energy of the solver's motion after its first frame, where Verlet takes back and the
    /// edit happens, J.
    pub motion_handed: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// The energy of a cloth's motion: its kinetic energy and what its springs hold, which turn
/// into each other as it swings, J.
fn motion(mesh: &ClothMesh, state: &ClothState, params: &StepParams) -> f64 {
    energy::kinetic(mesh, state, params) + energy::spring(mesh, state, params)
}

/// The swap case at frame `at`: Verlet (the course's 30 steps per frame) runs from rest to
/// frame `at`; then the solver takes over at `steps` per frame, is handed back to Verlet after
/// one frame, and, instead, has its steps per frame edited to `steps + 1`.
pub(crate) fn swap(
    scene: &Arc<Scene>,
    params: StepParams,
    entry: &SolverEntry,
    options: &Value,
    steps: u32,
    at: usize,
) -> Result<SwapFigures, CheckError> {
    let started = Instant::now();
    let mesh = &scene.mesh;
    let defaults = json!({});
    let reference = Verlet::ENTRY.steps_per_frame();
    let verlet_params = StepParams {
        steps_per_frame: reference,
        ..params
    };
    let failed = |what: &str, e: &dyn std::fmt::Display| CheckError::Swap {
        solver: entry.name().to_owned(),
        frame: at,
        reason: format!("{what}: {e}"),
    };
    let mut verlet = Stepper::new(scene, verlet_params, &Verlet::ENTRY, &defaults)?;
    for _ in 0..at {
        verlet.frame().map_err(|e| failed("Verlet", &e))?;
    }
    let taken = verlet.state().clone();
    let motion_to = motion(mesh, &taken, verlet.params());
    verlet.frame().map_err(|e| failed("Verlet", &e))?;
    let ke_verlet = energy::kinetic(mesh, verlet.state(), verlet.params());

    let at_frames = at as u64;
    let mut solver = Stepper::from_state(scene, verlet_params, entry, options, taken, at_frames)?;
    solver.swap(entry, options, steps)?;
    solver
        .frame()
        .map_err(|e| failed("the solver's first frame", &e))?;
    let ke_to = energy::kinetic(mesh, solver.state(), solver.params());
    let handed = solver.state().clone();
    let solver_params = *solver.params();
    let motion_handed = motion(mesh, &handed, &solver_params);
    solver
        .frame()
        .map_err(|e| failed("the solver's second frame", &e))?;
    let ke_solver = energy::kinetic(mesh, solver.state(), solver.params());

    let mut back = Stepper::from_state(
        scene,
        solver_params,
        entry,
        options,
        handed.clone(),
        at_frames + 1,
    )?;
    back.swap(&Verlet::ENTRY, &defaults, reference)?;
    back.frame().map_err(|e| failed("Verlet taking back", &e))?;
    let ke_back = energy::kinetic(mesh, back.state(), back.params());

    let mut edited =
        Stepper::from_state(scene, solver_params, entry, options, handed, at_frames + 1)?;
    edited.set_steps(steps + 1)?;
    edited
        .frame()
        .map_err(|e| failed("the solver after the edit", &e))?;
    let ke_edit = energy::kinetic(mesh, edited.state(), edited.params());
    Ok(SwapFigures {
        verlet: ke_verlet,
        to: ke_to,
        solver: ke_solver,
        back: ke_back,
        edit: ke_edit,
        edit_steps: steps + 1,
        motion_to,
        motion_handed,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// Seconds of the wind case: the curtain has caught the wind and come to rest in it (the
/// course's drag takes a swing down by e^-16 in 3 s).
pub const WIND_SECONDS: f64 = 3.0;

/// What the wind case measured of one solver.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Downwind {
    /// How far the curtain's centre went along the wind, m.
    pub distance: f64,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
    /// Wall-clock seconds.
    pub seconds: f64,
}

/// `entry`'s solver on `scene` with `params` under `wind` for [`WIND_SECONDS`]: how far the
/// centre point went along the wind.
pub(crate) fn downwind(
    scene: &Arc<Scene>,
    params: StepParams,
    entry: &SolverEntry,
    options: &Value,
    wind: Vec3,
) -> Result<Downwind, CheckError> {
    let started = Instant::now();
    let params = StepParams {
        wind: cloth_mesh::Wind {
            velocity: wind,
            ..cloth_mesh::Wind::default()
        },
        ..params
    };
    let mut stepper = Stepper::new(scene, params, entry, options)?;
    let mesh = &scene.mesh;
    let centre = mesh.index(mesh.nw() / 2, mesh.nh() / 2);
    let start = stepper.state().positions[centre];
    let along = wind.try_normalize(0.0).unwrap_or_else(Vec3::zeros);
    let mut error = None;
    for frame in 1..=frames_in(WIND_SECONDS, &params) {
        if let Err(e) = stepper.frame() {
            error = Some(format!("frame {frame}: {e}"));
            break;
        }
        if let Some(i) = stepper.state().first_non_finite() {
            error = Some(format!("frame {frame}: point {i} is not finite"));
            break;
        }
    }
    Ok(Downwind {
        distance: (stepper.state().positions[centre] - start).dot(&along),
        error,
        seconds: started.elapsed().as_secs_f64(),
    })
}
