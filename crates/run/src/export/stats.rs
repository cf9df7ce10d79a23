//! The per-frame table of numbers: what a run did, frame by frame, for plotting elsewhere.
//!
//! CSV (a header line, then one line per frame) or JSON (an array of one object per frame),
//! with the same columns in both:
//!
//! | column | meaning |
//! |---|---|
//! | `frame` | frames since the scene's start (a run `--from` a state goes on counting) |
//! | `time_s` | simulated seconds since the scene's start |
//! | `kinetic_energy_j` | kinetic energy, joules |
//! | `max_stretch` | the largest spring length over its rest length (1.1: at the stretch limit) |
//! | `lowest_y_m` | the lowest point's height, metres |
//! | `centre_y_m` | the height of the grid's centre point, metres |
//! | `steps` | solver steps taken in the frame |
//! | `wall_s` | wall-clock seconds the frame took to step (empty in CSV / null in JSON for the start, which took no step) |
//!
//! Every column but `wall_s` is the same bit for bit for the same scene, settings and frames;
//! `wall_s` is last so a comparison can drop it.

use std::io::Write;
use std::path::Path;

use cloth_mesh::{ClothMesh, ClothState};
use cloth_solver::{kinetic_energy, max_stretch_ratio};
use serde::Serialize;

use super::write_error;
use crate::output::StreamFile;

/// The columns, in order, as the CSV header names them.
pub const COLUMNS: [&str; 8] = [
    "frame",
    "time_s",
    "kinetic_energy_j",
    "max_stretch",
    "lowest_y_m",
    "centre_y_m",
    "steps",
    "wall_s",
];

/// One frame's row.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StatsRow {
    /// Frames since the scene's start.
    pub frame: u64,
    /// Simulated seconds since the scene's start.
    pub time_s: f64,
    /// Kinetic energy, J.
    pub kinetic_energy_j: f64,
    /// Largest spring length / rest length.
    pub max_stretch: f64,
    /// The lowest point's height (y), m.
    pub lowest_y_m: f64,
    /// The grid centre point's height (y), m.
    pub centre_y_m: f64,
    /// Solver steps taken in the frame.
    pub steps: u64,
    /// Wall-clock seconds the frame took, when measured.
    pub wall_s: Option<f64>,
}

impl StatsRow {
    /// The row of `state` at the end of frame `frame` (simulated time `time_s`), after
    /// `steps` steps of `dt` seconds with points of `point_mass` kilograms.
    #[allow(clippy::too_many_arguments)]
    pub fn measure(
        mesh: &ClothMesh,
        state: &ClothState,
        point_mass: f64,
        dt: f64,
        frame: u64,
        time_s: f64,
        steps: u64,
        wall_s: Option<f64>,
    ) -> Self {
        let centre = mesh.index(mesh.nw() / 2, mesh.nh() / 2);
        Self {
            frame,
            time_s,
            kinetic_energy_j: kinetic_energy(state, point_mass, dt),
            max_stretch: max_stretch_ratio(mesh, state),
            lowest_y_m: state
                .positions
                .iter()
                .map(|p| p.y)
                .fold(f64::INFINITY, f64::min),
            centre_y_m: state.positions.get(centre).map_or(f64::NAN, |p| p.y),
            steps,
            wall_s,
        }
    }

    /// The row as a CSV line (shortest round-tripping decimals), newline included.
    pub fn csv(&self) -> String {
        let wall = self.wall_s.map(|w| w.to_string()).unwrap_or_default();
        format!(
            "{},{},{},{},{},{},{},{wall}\n",
            self.frame,
            self.time_s,
            self.kinetic_energy_j,
            self.max_stretch,
            self.lowest_y_m,
            self.centre_y_m,
            self.steps
        )
    }
}

/// How the table is written, from the file name's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StatsFormat {
    /// Comma-separated values with a header line.
    Csv,
    /// A JSON array of one object per frame.
    Json,
}

impl StatsFormat {
    /// The format `path` asks for.
    ///
    /// # Errors
    /// An extension other than `.csv` or `.json`, naming the file and what is allowed.
    pub fn of(path: &Path) -> anyhow::Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("csv") => Ok(Self::Csv),
            Some("json") => Ok(Self::Json),
            _ => anyhow::bail!(
                "--stats {}: the file name must end in .csv or .json",
                path.display()
            ),
        }
    }
}

/// A table being written row by row to its file, put in place by [`StatsTable::finish`].
#[derive(Debug)]
pub struct StatsTable {
    format: StatsFormat,
    file: StreamFile,
    rows: u64,
}

impl StatsTable {
    /// Starts the table at `path` (its format from the extension).
    ///
    /// # Errors
    /// An unknown extension, or a file that cannot be created (see [`StreamFile::create`]).
    pub fn create(path: &Path) -> anyhow::Result<Self> {
        let format = StatsFormat::of(path)?;
        let mut file = StreamFile::create(path)?;
        let head = match format {
            StatsFormat::Csv => format!("{}\n", COLUMNS.join(",")),
            StatsFormat::Json => "[".to_owned(),
        };
        file.write_all(head.as_bytes())
            .map_err(|e| write_error(path, e))?;
        Ok(Self {
            format,
            file,
            rows: 0,
        })
    }

    /// Appends `row`.
    ///
    /// # Errors
    /// A failed write (a full disk), naming the file.
    pub fn push(&mut self, row: &StatsRow) -> anyhow::Result<()> {
        let text = match self.format {
            StatsFormat::Csv => row.csv(),
            StatsFormat::Json => {
                let sep = if self.rows == 0 { "\n" } else { ",\n" };
                format!("{sep}{}", serde_json::to_string(row)?)
            }
        };
        self.rows += 1;
        self.file
            .write_all(text.as_bytes())
            .map_err(|e| write_error(self.file.path(), e))
    }

    /// Ends the table and puts it in place.
    ///
    /// # Errors
    /// A failed write or rename, naming the file.
    pub fn finish(mut self) -> anyhow::Result<()> {
        if self.format == StatsFormat::Json {
            self.file
                .write_all(b"\n]\n")
                .map_err(|e| write_error(self.file.path(), e))?;
        }
        self.file.finish().map(drop)
    }

    /// Writes `rows` as a whole table at `path`.
    ///
    /// # Errors
    /// As [`StatsTable::create`], [`StatsTable::push`] and [`StatsTable::finish`].
    pub fn write(path: &Path, rows: &[StatsRow]) -> anyhow::Result<()> {
        let mut table = Self::create(path)?;
        for r in rows {
            table.push(r)?;
        }
        table.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use cloth_mesh::{GridSpec, Vec3};

    fn row(frame: u64, wall: Option<f64>) -> StatsRow {
        StatsRow {
            frame,
            time_s: frame as f64 / 90.0,
            kinetic_energy_j: 0.5,
            max_stretch: 1.01,
            lowest_y_m: -0.25,
            centre_y_m: 0.5,
            steps: 30,
            wall_s: wall,
        }
    }

    #[test]
    fn a_csv_table_has_the_header_and_one_line_per_frame() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.csv");
        StatsTable::write(&path, &[row(1, Some(0.002)), row(2, None)]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], COLUMNS.join(","));
        assert_eq!(lines.len(), 3);
        assert_eq!(
            lines[1].split(',').count(),
            COLUMNS.len(),
            "every column present"
        );
        assert!(
            lines[2].ends_with(",30,"),
            "unknown wall time is empty: {}",
            lines[2]
        );
    }

    #[test]
    fn a_json_table_is_an_array_of_rows_with_the_columns_as_keys() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.json");
        StatsTable::write(&path, &[row(1, Some(0.002)), row(2, None)]).unwrap();
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let rows = v.as_array().unwrap();
        assert_eq!(rows.len(), 2);
        for c in COLUMNS {
            assert!(rows[0].get(c).is_some(), "{c}");
        }
        assert!(rows[1]["wall_s"].is_null());
        // No rows is still valid JSON.
        StatsTable::write(&path, &[]).unwrap();
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(v, serde_json::json!([]));
    }

    #[test]
    fn an_unknown_extension_is_refused_naming_the_allowed_ones() {
        let e = StatsTable::create(Path::new("stats.txt"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("stats.txt") && e.contains(".csv or .json"),
            "{e}"
        );
    }

    #[test]
    fn the_row_measures_heights_of_the_lowest_and_the_centre_point() {
        let mesh = ClothMesh::new(&GridSpec {
            num_width_points: 3,
            num_height_points: 3,
            ..GridSpec::default()
        })
        .unwrap();
        let mut state = ClothState::new(&mesh);
        state.positions[4].y = 7.0;
        state.positions[8] = Vec3::new(0.0, -3.0, 0.0);
        state.last.clone_from(&state.positions);
        let r = StatsRow::measure(&mesh, &state, 1.0, 0.01, 1, 0.01, 30, None);
        assert_eq!(
            r.centre_y_m, 7.0,
            "point (1, 1) is the centre of a 3 x 3 grid"
        );
        assert_eq!(r.lowest_y_m, -3.0);
        assert_eq!(
            r.kinetic_energy_j, 0.0,
            "positions equal last positions: at rest"
        );
    }
}
