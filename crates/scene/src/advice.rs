//! What to change when a run goes non-finite, in the scene's own keys.
//!
//! A solver only knows that a point stopped being finite; the cause is in the scene. The usual
//! one for the explicit (Verlet) solver is a step too long for the cloth's stiffness: a point
//! of mass `m` held by springs of total stiffness `k` oscillates at `w = sqrt(k / m)`, and an
//! explicit step `h` is stable only while `h * w` stays below about 2. The point mass comes from
//! `cloth.density` and the cloth's size and point count, the stiffness from `cloth.ks` and the
//! enabled springs (a point has four structural, four shearing and four bending neighbours,
//! bending at 0.2 ks), the step from `simulation.frames_per_sec` and
//! `simulation.simulation_steps`. So the advice names whichever of those is out of line, rather
//! than always blaming `ks`. Gravity far beyond any real one overflows the positions by itself.
//!
//! The keys named are the scene file's, which `--set` takes too.

use cloth_mesh::StepParams;

use crate::Scene;
use crate::number::{approx, show};

/// The course's cloth, for saying which value is out of line.
const COURSE_DENSITY: f64 = 150.0;
const COURSE_KS: f64 = 5000.0;
/// The course's cloth: 1 m x 1 m over 50 x 50 points.
const COURSE_AREA_PER_POINT: f64 = 1.0 / 2500.0;
/// Gravity beyond this (a hundred thousand times the Earth's) is named as the cause.
const ABSURD_GRAVITY: f64 = 1e6;
/// The most `simulation.simulation_steps` the scene allows.
const MAX_STEPS: f64 = 10_000.0;

/// Why a run of `scene` with `params` (the scene's, or as edited since) most likely went
/// non-finite, and what to change; `explicit` is true for the Verlet solver, whose step has a
/// stability limit.
#[must_use]
pub fn divergence_advice(scene: &Scene, params: &StepParams, explicit: bool) -> String {
    // The largest component, not the length: squaring 1e308 would overflow.
    let g = params.gravity.amax();
    if g > ABSURD_GRAVITY {
        return format!(
            "simulation.gravity is [{}, {}, {}] m/s^2 (the Earth's is 9.8 in size), which \
             drives the positions past what a 64-bit float holds; use a gravity of ordinary size",
            show(params.gravity.x),
            show(params.gravity.y),
            show(params.gravity.z),
        );
    }
    let spec = scene.mesh.spec();
    let points = scene.mesh.len().max(1) as f64;
    let area_per_point = spec.width * spec.height / points;
    let mass = params.density * area_per_point;
    let neighbours = f64::from(u8::from(params.structural)) * 4.0
        + f64::from(u8::from(params.shearing)) * 4.0
        + f64::from(u8::from(params.bending)) * 4.0 * 0.2;
    let stiffness = params.ks * neighbours;
    let step = 1.0 / (params.frames_per_sec * f64::from(params.steps_per_frame));
    let omega = (stiffness / mass).sqrt();
    let limit = 2.0 / omega;
    if explicit && stiffness > 0.0 && step > limit {
        let needed = (f64::from(params.steps_per_frame) * step / limit).ceil();
        let odd = out_of_line(params, area_per_point);
        let remedy = odd
            .as_ref()
            .map_or("lower cloth.ks or raise cloth.density", |(_, remedy)| {
                remedy
            });
        let fix = if needed <= MAX_STEPS {
            format!("raise simulation.simulation_steps to at least {needed}, or {remedy}")
        } else {
            format!("that would take more than 10000 simulation.simulation_steps, so {remedy}")
        };
        return format!(
            "the step is too long for this cloth's stiffness{}: a point weighs {} kg \
             (cloth.density {} kg/m^2 over a {} m x {} m cloth of {} points) and its springs \
             pull with about {} N/m (cloth.ks {} N/m), so the verlet solver needs steps shorter \
             than about {} s, but they are {} s (1 / (simulation.frames_per_sec {} x \
             simulation.simulation_steps {})); {fix}",
            odd.as_ref()
                .map(|(what, _)| format!(" ({what})"))
                .unwrap_or_default(),
            approx(mass),
            show(params.density),
            show(spec.width),
            show(spec.height),
            scene.mesh.len(),
            approx(stiffness),
            show(params.ks),
            approx(limit),
            approx(step),
            show(params.frames_per_sec),
            params.steps_per_frame,
        );
    }
    match out_of_line(params, area_per_point) {
        Some((odd, _)) => format!(
            "the step is within the solver's stability limit, but {odd}; bring it nearer to \
             the course's, or use more simulation.simulation_steps"
        ),
        None => "the step is within the solver's stability limit and no value is far from \
                 the course's cloth (cloth.ks 5000 N/m, cloth.density 150 kg/m^2, a 1 m cloth \
                 of 50 x 50 points); more simulation.simulation_steps or a lower cloth.ks \
                 usually help"
            .to_owned(),
    }
}

/// The input of `scene` (with `params`) furthest from the course's cloth, when one is a hundred
/// times off or more, with what would bring it back: `("cloth.density is 1e-300 kg/m^2, where
/// the course's cloth has 150", "raise cloth.density")`. A run that made energy from nothing
/// within the step's stability limit is most often explained by it.
#[must_use]
pub fn unusual_value(scene: &Scene, params: &StepParams) -> Option<(String, &'static str)> {
    let spec = scene.mesh.spec();
    let area_per_point = spec.width * spec.height / scene.mesh.len().max(1) as f64;
    out_of_line(params, area_per_point)
}

/// `cloth.density is 1e-300 kg/m^2, where the course's cloth has 150` for the input furthest
/// from the course's cloth in the direction that shortens the stable step, when one is a
/// hundred times off or more, with what would bring it back.
fn out_of_line(params: &StepParams, area_per_point: f64) -> Option<(String, &'static str)> {
    // Each factor above 1 shortens the stable step by its square root.
    let candidates = [
        (
            COURSE_DENSITY / params.density,
            format!("cloth.density is {} kg/m^2", show(params.density)),
            "150",
            "raise cloth.density",
        ),
        (
            params.ks / COURSE_KS,
            format!("cloth.ks is {} N/m", show(params.ks)),
            "5000",
            "lower cloth.ks",
        ),
        (
            COURSE_AREA_PER_POINT / area_per_point,
            format!(
                "each point carries {} m^2 of cloth (cloth.width x cloth.height / points)",
                approx(area_per_point)
            ),
            "0.0004",
            "give each point more cloth (a larger cloth.width and cloth.height, or fewer points)",
        ),
    ];
    candidates
        .into_iter()
        .filter(|(f, ..)| f.is_finite() && *f >= 100.0)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, what, course, remedy)| {
            (
                format!("{what}, where the course's cloth has {course}"),
                remedy,
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::load;

    fn advice(sets: &[&str]) -> String {
        let sets: Vec<String> = sets.iter().map(|s| (*s).to_owned()).collect();
        let scene = load("pinned4", &sets).unwrap();
        divergence_advice(&scene, &scene.params, true)
    }

    #[test]
    fn stiff_springs_are_blamed_with_the_steps_that_would_hold_them() {
        // ks 1e9: k = 8.8e9 N/m on 0.06 kg gives w = 3.83e5 /s, a limit of 5.22e-6 s against
        // steps of 3.70e-4 s: 70.9 times too long, so 30 steps become at least 2128.
        let a = advice(&["cloth.ks=1e9"]);
        assert!(
            a.contains("cloth.ks is 1e9 N/m, where the course's cloth has 5000"),
            "{a}"
        );
        assert!(
            a.contains("simulation.simulation_steps to at least 2128"),
            "{a}"
        );
        assert!(!a.contains("reset"), "{a}");
    }

    #[test]
    fn a_tiny_density_or_a_tiny_cloth_is_blamed_instead_of_ks() {
        let a = advice(&["cloth.density=1e-300"]);
        assert!(a.contains("cloth.density is 1e-300 kg/m^2"), "{a}");
        assert!(a.ends_with("so raise cloth.density"), "{a}");
        let a = advice(&["cloth.width=1e-9", "cloth.height=1e-9"]);
        assert!(a.contains("each point carries 4e-22 m^2"), "{a}");
        assert!(
            a.ends_with("a larger cloth.width and cloth.height, or fewer points)"),
            "{a}"
        );
    }

    #[test]
    fn absurd_gravity_is_blamed_on_gravity() {
        let a = advice(&["simulation.gravity=[0,-1e308,0]"]);
        assert!(
            a.starts_with("simulation.gravity is [0, -1e308, 0] m/s^2"),
            "{a}"
        );
    }

    #[test]
    fn a_stable_step_does_not_blame_the_step() {
        let a = advice(&[]);
        assert!(a.starts_with("the step is within"), "{a}");
        assert!(a.contains("no value is far from the course's cloth"), "{a}");
        let scene = load("pinned4", &["cloth.ks=1e9".to_owned()]).unwrap();
        let implicit = divergence_advice(&scene, &scene.params, false);
        assert!(implicit.starts_with("the step is within"), "{implicit}");
        assert!(implicit.contains("cloth.ks is 1e9 N/m"), "{implicit}");
    }
}
