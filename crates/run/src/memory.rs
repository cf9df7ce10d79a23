//! Memory checked before it is asked for: a run is refused, naming what it needs and the limit,
//! when its solver's estimate ([`SolverEntry::memory_estimate`]), the cloth and its states and
//! the frames it draws come to more than `--max-memory`, or by default than the memory the
//! system has available. A refused run allocates nothing large, so it cannot abort.
//!
//! This check is what keeps the solvers' own allocations from outgrowing the machine: every
//! solver states its needs through its registry entry, and the run is refused before any
//! solver is built, so the solver crates do not probe the system themselves.

use std::fmt::Display;
use std::path::Path;

use cloth_mesh::{ClothMesh, Vec3};
use cloth_render::{Mode, Renderer};
use cloth_solver::SolverEntry;
use serde_json::Value;

/// Every limit on the memory a new allocation of this process can have, bytes; `None` where a
/// limit does not apply or is not known.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Limits {
    /// Linux's `MemAvailable`: free memory plus the caches it can drop. Swap may stretch it,
    /// so `--max-memory` overrides it.
    pub system: Option<u64>,
    /// The address-space limit (`ulimit -v`, `RLIMIT_AS`) less what is mapped already (the
    /// program, its libraries, thread stacks): past it an allocation fails, whatever swap
    /// there is.
    pub address_space: Option<u64>,
    /// The smallest memory limit less usage of the control groups (v1 or v2) the process runs
    /// in and their ancestors: past it the kernel kills the process.
    pub cgroup: Option<u64>,
}

impl Limits {
    /// The limits this process lives under now.
    #[must_use]
    pub fn now() -> Self {
        let read = |p: &str| std::fs::read_to_string(p).ok();
        let system = read("/proc/meminfo").and_then(|t| kib_line(&t, "MemAvailable:"));
        let mapped = read("/proc/self/status").and_then(|t| kib_line(&t, "VmSize:"));
        let address_space = address_space_limit().map(|l| l.saturating_sub(mapped.unwrap_or(0)));
        let cgroup =
            read("/proc/self/cgroup").and_then(|t| cgroup_room(&t, Path::new("/sys/fs/cgroup")));
        Self {
            system,
            address_space,
            cgroup,
        }
    }

    /// The tightest limit, with its description and what to change, counting `system` only
    /// when `with_system` (not with `--max-memory`).
    fn tightest(&self, with_system: bool) -> Option<(u64, String, &'static str)> {
        let mut all = Vec::new();
        if with_system && let Some(a) = self.system {
            all.push((
                a,
                format!("the {} of memory available", human_bytes(a)),
                "free some memory (--max-memory SIZE sets the limit instead)",
            ));
        }
        if let Some(a) = self.address_space {
            all.push((
                a,
                format!(
                    "the {} the address-space limit (ulimit -v) leaves",
                    human_bytes(a)
                ),
                "raise the address-space limit (ulimit -v)",
            ));
        }
        if let Some(a) = self.cgroup {
            all.push((
                a,
                format!(
                    "the {} the control group's memory limit leaves",
                    human_bytes(a)
                ),
                "raise the control group's memory limit",
            ));
        }
        all.into_iter().min_by_key(|(a, _, _)| *a)
    }
}

/// The memory a new allocation of this process can have, bytes: the tightest of [`Limits`].
/// `None` where none is known (other systems); only the allocations themselves can fail there.
#[must_use]
pub fn available_memory() -> Option<u64> {
    Limits::now().tightest(true).map(|(a, _, _)| a)
}

/// The value of a `KEY:  N kB` line of a `/proc` file, bytes.
fn kib_line(text: &str, key: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line
        .trim_start_matches(key)
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    kib.checked_mul(1024)
}

/// A control group's limit that means "none": v1 writes the largest page-aligned `i64`.
const NO_CGROUP_LIMIT: u64 = 1 << 60;

/// The room left under the memory limits of the control groups named in `proc_cgroup` (the
/// text of `/proc/self/cgroup`) and their ancestors, under the cgroup file systems at `root`:
/// the smallest `limit - usage`. v2 (`0::/path`) reads `memory.max` and `memory.current`, v1
/// (`N:memory:/path`) `memory.limit_in_bytes` and `memory.usage_in_bytes`. A group whose files
/// are not visible (a container sees its own group as the root) counts as no limit.
fn cgroup_room(proc_cgroup: &str, root: &Path) -> Option<u64> {
    let mut room: Option<u64> = None;
    for line in proc_cgroup.lines() {
        let mut parts = line.splitn(3, ':');
        let (Some(id), Some(controllers), Some(path)) = (parts.next(), parts.next(), parts.next())
        else {
            continue;
        };
        let (base, limit_file, usage_file) = if id == "0" && controllers.is_empty() {
            let unified = root.join("unified");
            let base = if unified.join("cgroup.controllers").exists() {
                unified
            } else {
                root.to_owned()
            };
            (base, "memory.max", "memory.current")
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                root.join("memory"),
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        // The group itself and each ancestor up to the root: a parent's limit binds too.
        let mut dir = base.join(path.trim_start_matches('/'));
        loop {
            let number = |f: &str| {
                std::fs::read_to_string(dir.join(f))
                    .ok()
                    .and_then(|t| t.trim().parse::<u64>().ok())
            };
            if let Some(limit) = number(limit_file).filter(|&l| l < NO_CGROUP_LIMIT) {
                let left = limit.saturating_sub(number(usage_file).unwrap_or(0));
                room = Some(room.map_or(left, |r| r.min(left)));
            }
            if dir == base || !dir.pop() || !dir.starts_with(&base) {
                break;
            }
        }
    }
    room
}

/// The soft limit on this process's address space, bytes, when there is one.
#[cfg(unix)]
fn address_space_limit() -> Option<u64> {
    use nix::sys::resource::{RLIM_INFINITY, Resource, getrlimit};
    match getrlimit(Resource::RLIMIT_AS) {
        Ok((soft, _)) if soft != RLIM_INFINITY => Some(soft),
        _ => None,
    }
}

#[cfg(not(unix))]
fn address_space_limit() -> Option<u64> {
    None
}

/// `bytes` as a short size in binary units (`512 bytes`, `10.7 GiB`).
#[must_use]
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// What `--max-memory` takes, for messages and help.
const SIZE_FORM: &str = "a number of bytes with an optional K, M, G or T suffix (powers of \
                         1024), such as 512M, 4G or 1.5G";

/// Parses a size as `--max-memory` takes it: a positive number with an optional K, M, G or T
/// suffix (powers of 1024, upper or lower case, optionally followed by `B` or `iB`).
///
/// # Errors
/// A message naming the value and what is allowed.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let bad = || format!("{text:?} is not a size: it must be {SIZE_FORM}");
    let t = text.trim();
    let digits = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(digits);
    let unit = unit.trim().to_ascii_lowercase();
    let unit = unit
        .strip_suffix("ib")
        .or_else(|| unit.strip_suffix('b'))
        .unwrap_or(&unit);
    let scale: u64 = match unit {
        "" => 1,
        "k" => 1 << 10,
        "m" => 1 << 20,
        "g" => 1 << 30,
        "t" => 1 << 40,
        _ => return Err(bad()),
    };
    let value: f64 = number.parse().map_err(|_| bad())?;
    let bytes = (value * scale as f64).round();
    // NOTE: below 2^64 exactly: `as u64` would saturate a larger value silently.
    if !(1.0..18_446_744_073_709_551_616.0).contains(&bytes) {
        return Err(format!(
            "{text:?} is not a size this machine can have: it must be more than 0 bytes and \
             less than 16 EiB ({SIZE_FORM})"
        ));
    }
    Ok(bytes as u64)
}

/// `the NAME solver`, for [`check`]'s messages.
pub fn solver(entry: &SolverEntry) -> String {
    format!("the {} solver", entry.name())
}

/// Bytes a run needs, by what holds them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Need {
    /// The solver's scratch and caches, as its entry states them.
    pub solver: u64,
    /// The mesh and the copies of the cloth's state the run keeps.
    pub cloth: u64,
    /// Renderer buffers and frames.
    pub drawing: u64,
}

impl Need {
    /// What a run of `entry` with `options` on `mesh` needs, keeping `states` copies of the
    /// cloth's state and drawing into `drawing` bytes of buffers (see [`drawing`]).
    pub fn new(
        entry: &SolverEntry,
        options: &Value,
        mesh: &ClothMesh,
        states: u64,
        drawing: u64,
    ) -> Self {
        Self {
            solver: entry.memory_estimate(mesh, options),
            cloth: mesh_bytes(mesh).saturating_add(states.saturating_mul(state_bytes(mesh))),
            drawing,
        }
    }

    /// The whole.
    pub fn total(&self) -> u64 {
        self.solver
            .saturating_add(self.cloth)
            .saturating_add(self.drawing)
    }
}

/// Bytes of `mesh`'s arrays: start positions, pins, springs and triangles.
pub fn mesh_bytes(mesh: &ClothMesh) -> u64 {
    let points = mesh.len() * (size_of::<Vec3>() + size_of::<bool>());
    let springs = size_of_val(mesh.springs());
    let triangles = size_of_val(mesh.triangles());
    (points + springs + triangles) as u64
}

/// Bytes of one state of `mesh`: its positions and last positions.
pub fn state_bytes(mesh: &ClothMesh) -> u64 {
    (2 * mesh.len() * size_of::<Vec3>()) as u64
}

/// Bytes of `panels` frames of `cells` character cells each, drawn in `mode` from a cloth of
/// `points` points, by one renderer.
pub fn drawing(points: usize, panels: usize, cells: usize, mode: Mode) -> u64 {
    let frames = panels.saturating_mul(cells);
    // One renderer draws every panel in turn: its buffers are one panel's.
    Renderer::memory_estimate(points, cells, mode).saturating_add(Renderer::memory_estimate(
        0,
        frames,
        Mode::Ascii,
    ))
}

/// Copies of the cloth's state the live UI keeps: the displayed simulation's state and last
/// good state, the worker's two, and the snapshot the worker hands over.
const UI_STATES: u64 = 5;

/// Cells of the largest terminal the live UI's estimate allows for: its panes share them.
const UI_CELLS: usize = 400 * 120;

/// What the live UI needs to run `entry` with `options` on `mesh`.
pub fn ui_need(entry: &SolverEntry, options: &Value, mesh: &ClothMesh) -> Need {
    let drawing = drawing(mesh.len(), 1, UI_CELLS, Mode::Braille);
    Need::new(entry, options, mesh, UI_STATES, drawing)
}

/// How a scene's cloth is made smaller, for [`check`]'s advice.
pub const SMALLER_SCENE: &str = "a smaller grid (cloth.num_width_points, cloth.num_height_points)";

/// Refuses the run described by `need` when it exceeds `max` bytes (`--max-memory`), or, when
/// there is no `max`, the memory the system has available (no check where that is unknown).
///
/// # Errors
/// A message naming `origin`, `who` (`the verlet solver`), the cloth's size, the estimate and
/// its parts, and the limit, with what to change: `smaller` (see [`SMALLER_SCENE`]) or the
/// limit.
pub fn check(
    origin: impl Display,
    who: &str,
    mesh: &ClothMesh,
    need: Need,
    (max, smaller): (Option<u64>, &str),
) -> anyhow::Result<()> {
    // NOTE: `--max-memory` replaces only the system's available memory (swap may stretch it);
    // an address-space or control-group limit aborts or kills a run past it, whatever is asked.
    let limits = Limits::now();
    let hard = limits.tightest(false);
    let (limit, what, raise) = match (max, hard) {
        (Some(max), Some(hard)) if hard.0 < max => hard,
        (Some(max), _) => (
            max,
            format!("the --max-memory limit of {}", human_bytes(max)),
            "raise --max-memory",
        ),
        (None, _) => match limits.tightest(true) {
            Some(t) => t,
            None => return Ok(()),
        },
    };
    if need.total() <= limit {
        return Ok(());
    }
    let drawing = if need.drawing > 0 {
        format!(", {} for drawing", human_bytes(need.drawing))
    } else {
        String::new()
    };
    anyhow::bail!(
        "{origin}: {who} on this {} x {} cloth needs about {} ({} for the solver, {} for the \
         cloth and its states{drawing}), more than {what}; use {smaller} or {raise}",
        mesh.nw(),
        mesh.nh(),
        human_bytes(need.total()),
        human_bytes(need.solver),
        human_bytes(need.cloth),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_solver::Verlet;

    #[test]
    fn mem_available_is_read_in_bytes_from_meminfo() {
        let text = "MemTotal:       16318852 kB\nMemFree:  1 kB\nMemAvailable:    8159426 kB\n";
        let mem_available = |t: &str| kib_line(t, "MemAvailable:");
        assert_eq!(mem_available(text), Some(8_159_426 * 1024));
        assert_eq!(mem_available("MemTotal: 5 kB\n"), None);
        assert_eq!(mem_available("MemAvailable: lots kB\n"), None);
    }

    fn write(dir: &Path, file: &str, text: &str) {
        std::fs::create_dir_all(dir).unwrap();
        std::fs::write(dir.join(file), text).unwrap();
    }

    #[test]
    fn a_cgroup_v1_limit_of_the_group_or_an_ancestor_leaves_its_room() {
        let root = tempfile::tempdir().unwrap();
        let memory = root.path().join("memory");
        let group = memory.join("jobs/run7");
        write(&group, "memory.limit_in_bytes", "9223372036854771712\n");
        write(&group, "memory.usage_in_bytes", "100\n");
        let text = "4:memory:/jobs/run7\n3:cpuset:/\n0::/\n";
        // No limit anywhere (v1's "none" is the largest page-aligned i64).
        assert_eq!(cgroup_room(text, root.path()), None);
        // The parent's limit binds the child.
        write(&memory.join("jobs"), "memory.limit_in_bytes", "4096000\n");
        write(&memory.join("jobs"), "memory.usage_in_bytes", "96000\n");
        assert_eq!(cgroup_room(text, root.path()), Some(4_000_000));
        // A tighter limit on the group itself wins.
        write(&group, "memory.limit_in_bytes", "1000\n");
        assert_eq!(cgroup_room(text, root.path()), Some(900));
    }

    #[test]
    fn a_cgroup_v2_limit_is_read_from_memory_max_and_max_means_none() {
        let root = tempfile::tempdir().unwrap();
        let group = root.path().join("user.slice/app");
        write(root.path(), "cgroup.controllers", "memory\n");
        write(&group, "memory.max", "max\n");
        write(&group, "memory.current", "5\n");
        assert_eq!(cgroup_room("0::/user.slice/app\n", root.path()), None);
        write(&group, "memory.max", "2000000000\n");
        assert_eq!(
            cgroup_room("0::/user.slice/app\n", root.path()),
            Some(1_999_999_995)
        );
    }

    #[test]
    fn sizes_read_as_binary_units() {
        assert_eq!(human_bytes(512), "512 bytes");
        assert_eq!(human_bytes(1024 * 1024), "1.0 MiB");
        assert_eq!(human_bytes(11_488_248_432), "10.7 GiB");
    }

    #[test]
    fn sizes_take_binary_suffixes_and_refuse_anything_else() {
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("4G"), Ok(4 << 30));
        assert_eq!(parse_size("4gib"), Ok(4 << 30));
        assert_eq!(parse_size("1.5G"), Ok(3 << 29));
        assert_eq!(parse_size("100kB"), Ok(100 << 10));
        assert_eq!(parse_size("1000000"), Ok(1_000_000));
        assert_eq!(parse_size("2T"), Ok(2 << 40));
        for bad in ["", "M", "12X", "-1G", "1..2M", "1e3", "1G2"] {
            let e = parse_size(bad).unwrap_err();
            assert!(e.contains(&format!("{bad:?}")) && e.contains("512M"), "{e}");
        }
        for out_of_range in ["0", "0.1", "16777216T"] {
            let e = parse_size(out_of_range).unwrap_err();
            assert!(e.contains("more than 0 bytes"), "{e}");
        }
    }

    #[test]
    fn a_run_over_the_limit_is_refused_naming_the_estimate_and_the_limit() {
        let mesh = ClothMesh::pinned_grid(100).unwrap();
        let entry = Verlet::ENTRY;
        let need = Need::new(&entry, &Value::Null, &mesh, 1, 0);
        assert_eq!(
            need.solver,
            Verlet::memory_estimate(&mesh, 1, cloth_solver::ConstraintOrder::Faithful)
        );
        assert!(need.total() > 1 << 20);
        let e = check(
            "pinned4",
            &solver(&entry),
            &mesh,
            need,
            (Some(1 << 20), SMALLER_SCENE),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("pinned4: the verlet solver on this 100 x 100 cloth needs about ")
                && e.contains(&human_bytes(need.total()))
                && e.contains("the --max-memory limit of 1.0 MiB")
                && e.contains("cloth.num_width_points"),
            "{e}"
        );
        assert!(
            check(
                "pinned4",
                &solver(&entry),
                &mesh,
                need,
                (Some(need.total()), SMALLER_SCENE)
            )
            .is_ok()
        );
    }

    #[test]
    fn the_cloths_bytes_are_its_arrays() {
        let mesh = ClothMesh::pinned_grid(50).unwrap();
        assert_eq!(state_bytes(&mesh), 2 * 2500 * 24);
        let springs = size_of_val(mesh.springs()) as u64;
        assert_eq!(mesh_bytes(&mesh), 2500 * 25 + springs + 2 * 49 * 49 * 12);
        // Braille draws eight pixels a cell, ASCII one.
        assert!(drawing(2500, 1, 80 * 40, Mode::Braille) > drawing(2500, 1, 80 * 40, Mode::Ascii));
    }
}
