//! How a frame is drawn: mode, cell aspect, lighting and what to show.

use std::fmt;
use std::str::FromStr;

use cloth_mesh::Vec3;

use crate::RenderError;

/// How pixels become characters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Mode {
    /// One pixel per cell, intensity as a glyph ramp with ordered dithering.
    #[default]
    Ascii,
    /// Two pixels per cell (upper and lower half block) in foreground and background colour.
    /// Shading lives in the colours, so without colour it shows only which halves are covered.
    Half,
    /// 2 x 4 pixels per cell as braille dots, dithered.
    Braille,
}

impl Mode {
    /// Every mode.
    pub const ALL: [Mode; 3] = [Mode::Ascii, Mode::Half, Mode::Braille];
    /// The accepted spellings, for help and error messages.
    pub const NAMES: &'static str = "ascii, half or braille";

    /// Pixels per cell, `(across, down)`.
    #[must_use]
    pub fn pixels_per_cell(self) -> (usize, usize) {
        match self {
            Mode::Ascii => (1, 1),
            Mode::Half => (1, 2),
            Mode::Braille => (2, 4),
        }
    }

    /// The lowercase name, as typed on the command line.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Mode::Ascii => "ascii",
            Mode::Half => "half",
            Mode::Braille => "braille",
        }
    }
}

impl FromStr for Mode {
    type Err = RenderError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let t = s.trim().to_ascii_lowercase();
        Mode::ALL
            .into_iter()
            .find(|m| m.name() == t)
            .ok_or_else(|| RenderError::Unknown {
                what: "mode",
                value: s.to_owned(),
                allowed: Mode::NAMES,
            })
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Where the key light comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// A point light at this position, metres (the course's is at (0.5, 2, 2)).
    Point(Vec3),
    /// A light infinitely far away in this direction: the vector points from the scene towards
    /// the light (need not be unit length, must not be zero).
    Direction(Vec3),
}

impl Default for Light {
    fn default() -> Self {
        Light::Point(Vec3::new(0.5, 2.0, 2.0))
    }
}

/// Everything about how a frame is drawn except the camera.
///
/// Intensity at a surface point with unit normal `n` (flipped towards the viewer on a back
/// face), unit direction to the light `l` and to the viewer `v`:
/// `ambient + diffuse * max(0, n.l) + fill * max(0, n.v)`, clamped to [0, 1]. The fill term is
/// a headlight: it keeps faces turned away from the key light readable and makes folds show as
/// changes of slope towards the viewer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// How pixels become characters (default ascii).
    pub mode: Mode,
    /// Height of a character cell over its width (default 2.0; 0.25 to 8).
    pub cell_aspect: f64,
    /// The key light (default the course's point light at (0.5, 2, 2)).
    pub light: Light,
    /// Ambient intensity (default 0.08; 0 to 1).
    pub ambient: f64,
    /// Weight of the key light's Lambert term (default 0.62; 0 to 4).
    pub diffuse: f64,
    /// Weight of the headlight's Lambert term (default 0.3; 0 to 4). With the defaults the
    /// three weights sum to 1, so nothing saturates.
    pub fill: f64,
    /// Stretch each face's shades to the whole glyph ramp every frame (default true): the 2nd
    /// to 98th percentile of the visible front (or back) pixels map to the ends of the ramp,
    /// magnified at most 4 times (a narrower range is centred on the ramp). Shallow folds then
    /// span several glyphs instead of one.
    pub auto_contrast: bool,
    /// Draw the cloth's back face (default true); if false, back faces are not drawn at all.
    pub two_sided: bool,
    /// Mark pinned points with [`crate::PIN_GLYPH`] (default true).
    pub show_pins: bool,
    /// Draw spheres and planes (default true).
    pub show_colliders: bool,
    /// Where a hand holds the cloth, m: marked with [`crate::HAND_GLYPH`] when nothing hides
    /// it (default none).
    pub hand: Option<Vec3>,
    /// Draw a small axis legend in the bottom-left corner of orthographic views (default false).
    pub legend: bool,
    /// Fill in cell colours (default true). When the output will be shown without colour, set
    /// it false: half-block mode then shades with shade blocks that read without colour.
    pub color: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            mode: Mode::Ascii,
            cell_aspect: 2.0,
            light: Light::default(),
            ambient: 0.08,
            diffuse: 0.62,
            fill: 0.3,
            auto_contrast: true,
            two_sided: true,
            show_pins: true,
            show_colliders: true,
            hand: None,
            legend: false,
            color: true,
        }
    }
}

impl RenderOptions {
    /// Checks every number against its range.
    ///
    /// # Errors
    /// [`RenderError::BadOption`] naming the first bad field.
    pub fn validate(&self) -> Result<(), RenderError> {
        let check = |name, v: f64, lo: f64, hi: f64, allowed| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(RenderError::BadOption {
                    name,
                    value: v.to_string(),
                    allowed,
                })
            }
        };
        check(
            "cell_aspect",
            self.cell_aspect,
            0.25,
            8.0,
            "between 0.25 and 8 (cell height / width)",
        )?;
        check("ambient", self.ambient, 0.0, 1.0, "between 0 and 1")?;
        check("diffuse", self.diffuse, 0.0, 4.0, "between 0 and 4")?;
        check("fill", self.fill, 0.0, 4.0, "between 0 and 4")?;
        let v = match self.light {
            Light::Point(p) | Light::Direction(p) => p,
        };
        if let Some(h) = self.hand
            && !h.iter().all(|c| c.is_finite())
        {
            return Err(RenderError::BadOption {
                name: "hand",
                value: format!("{:?}", h.as_slice()),
                allowed: "three finite numbers",
            });
        }
        let zero_direction = matches!(self.light, Light::Direction(d) if d.norm() == 0.0);
        if !v.iter().all(|c| c.is_finite()) || zero_direction {
            return Err(RenderError::BadOption {
                name: "light",
                value: format!("{:?}", v.as_slice()),
                allowed: "three finite numbers (a direction must not be zero)",
            });
        }
        Ok(())
    }
}
