//! Regression: the faithful Verlet solver keeps the bits of the course's step.
//!
//! The fingerprints in `tests/fingerprints/` hold 90 frames of the course's `pinned2` and
//! `pinned4` scenes as the course's step computes them (`reference_step`, spring by spring). The
//! fast path promises the same operations in the same order, so the check is exact: every sampled
//! coordinate and every coordinate sum must have the fingerprint's bits.
//!
//! To re-take a fingerprint (only when the *model* deliberately changes, never to make a speed-up
//! pass), run `CLOTHSIM_BLESS_FINGERPRINTS=1 cargo test -p cloth-solver --test faithful_fingerprint`.

use std::fmt::Write as _;
use std::path::PathBuf;

use cloth_mesh::{ClothMesh, ClothState, GridSpec, Orientation};
use cloth_solver::{StepParams, Verlet, advance_frame, reference_step};

/// Frames simulated before the fingerprint is taken: one second of simulated time at 90 fps,
/// long enough for the cloth to fall, hit the stretch limit and wrinkle into self-contact.
const FRAMES: usize = 90;

/// Every `STRIDE`-th point is recorded (7 is prime to the grid width 50, so the samples cover
/// every column and every row), plus the sums of all coordinates, which catch a change anywhere.
const STRIDE: usize = 7;

/// The course's standard cloth (spec section 1): 1 x 1 m, 50 x 50 points, thickness 0.0095 m
/// read as the course's loader reads it (a 32-bit float), horizontal, with the given pins.
fn mesh(pins: &[(usize, usize)]) -> ClothMesh {
    ClothMesh::new(&GridSpec {
        width: 1.0,
        height: 1.0,
        num_width_points: 50,
        num_height_points: 50,
        thickness: f64::from(0.0095_f32),
        orientation: Orientation::Horizontal,
        pinned: pins.to_vec(),
        ..GridSpec::default()
    })
    .unwrap()
}

/// Course defaults: ks 5000, density 150, damping 0.2 %, 30 steps per frame at 90 fps,
/// self-collision on, stretch limit on.
fn params() -> StepParams {
    let params = StepParams::default();
    assert!(params.self_collision && params.stretch_limit);
    params
}

/// `FRAMES` frames of the fast Verlet from the start.
fn run_fast(mesh: &ClothMesh) -> ClothState {
    let params = params();
    let mut state = ClothState::new(mesh);
    let mut solver = Verlet::new();
    for _ in 0..FRAMES {
        advance_frame(&mut solver, mesh, &[], &params, &mut state).unwrap();
    }
    state
}

/// `FRAMES` frames of the course's step, written plainly, from the start.
fn run_reference(mesh: &ClothMesh) -> ClothState {
    let params = params();
    let mut state = ClothState::new(mesh);
    for _ in 0..FRAMES as u32 * params.steps_per_frame {
        reference_step(mesh, &[], &params, &mut state).unwrap();
    }
    state
}

/// A fingerprint: sampled points (index, position, last position) and coordinate sums.
#[derive(Debug)]
struct Fingerprint {
    samples: Vec<(usize, [f64; 6])>,
    sums: [f64; 6],
}

impl Fingerprint {
    fn of(state: &ClothState) -> Self {
        let row = |i: usize| {
            let (p, l) = (state.positions[i], state.last[i]);
            [p.x, p.y, p.z, l.x, l.y, l.z]
        };
        let mut sums = [0.0; 6];
        for i in 0..state.positions.len() {
            for (s, v) in sums.iter_mut().zip(row(i)) {
                *s += v;
            }
        }
        Self {
            samples: (0..state.positions.len())
                .step_by(STRIDE)
                .map(|i| (i, row(i)))
                .collect(),
            sums,
        }
    }

    /// One line per sample, `index x y z last_x last_y last_z`, then `sum ...`; numbers in Rust's
    /// shortest round-trip form, so parsing gives back the exact bits.
    fn to_text(&self, title: &str) -> String {
        let mut out = format!(
            "# {title}: the course's step after {FRAMES} frames; every {STRIDE}th point: \
             index x y z last_x last_y last_z (metres)\n"
        );
        for (i, v) in &self.samples {
            let _ = writeln!(
                out,
                "{i} {:?} {:?} {:?} {:?} {:?} {:?}",
                v[0], v[1], v[2], v[3], v[4], v[5]
            );
        }
        let s = self.sums;
        let _ = writeln!(
            out,
            "sum {:?} {:?} {:?} {:?} {:?} {:?}",
            s[0], s[1], s[2], s[3], s[4], s[5]
        );
        out
    }

    fn parse(text: &str) -> Self {
        let mut samples = Vec::new();
        let mut sums = None;
        for line in text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.is_empty())
        {
            let mut words = line.split_whitespace();
            let head = words.next().unwrap();
            let v: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
            let v: [f64; 6] = v.try_into().unwrap();
            if head == "sum" {
                sums = Some(v);
            } else {
                samples.push((head.parse().unwrap(), v));
            }
        }
        Self {
            samples,
            sums: sums.unwrap(),
        }
    }
}

fn path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fingerprints")
        .join(format!("{name}.txt"))
}

/// The fingerprint is taken from the reference step; both it and the fast path must give its
/// bits.
fn check(name: &str, pins: &[(usize, usize)]) {
    let mesh = mesh(pins);
    let file = path(name);
    if std::env::var_os("CLOTHSIM_BLESS_FINGERPRINTS").is_some() {
        let now = Fingerprint::of(&run_reference(&mesh));
        std::fs::create_dir_all(file.parent().unwrap()).unwrap();
        std::fs::write(&file, now.to_text(name)).unwrap();
    }
    let then = Fingerprint::parse(&std::fs::read_to_string(&file).unwrap());
    then.assert_same_bits(
        &Fingerprint::of(&run_reference(&mesh)),
        name,
        "reference step",
    );
    then.assert_same_bits(&Fingerprint::of(&run_fast(&mesh)), name, "fast Verlet");
}

impl Fingerprint {
    /// Every sampled coordinate and every sum of `now` has this fingerprint's bits.
    fn assert_same_bits(&self, now: &Self, name: &str, by: &str) {
        let then = self;
        let bits = |v: &[f64; 6]| v.map(f64::to_bits);
        assert_eq!(then.samples.len(), now.samples.len());
        for ((i, a), (j, b)) in then.samples.iter().zip(&now.samples) {
            assert_eq!(i, j);
            assert_eq!(
                bits(a),
                bits(b),
                "{name}, {by}: point {i} is not bit-identical: {a:?} vs {b:?}"
            );
        }
        assert_eq!(
            bits(&then.sums),
            bits(&now.sums),
            "{name}, {by}: coordinate sums moved from {:?} to {:?}",
            then.sums,
            now.sums
        );
    }
}

#[test]
fn pinned2_after_90_frames_matches_the_fingerprint() {
    check("pinned2", &[(0, 0), (49, 0)]);
}

#[test]
fn pinned4_after_90_frames_matches_the_fingerprint() {
    check("pinned4", &[(0, 0), (49, 0), (0, 49), (49, 49)]);
}
