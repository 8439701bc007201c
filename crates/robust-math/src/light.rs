//! Homogeneous light positions.

use glam::{Vec3, Vec4};

/// Errors from constructing or parsing a [`Light`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LightError {
    /// A component is NaN or infinite.
    #[error("light component {component} is {value}, but it must be finite")]
    NonFinite {
        /// `'x'`, `'y'`, `'z'` or `'w'`.
        component: char,
        /// The value found.
        value: f32,
    },
    /// `w` is negative; it would flip every sign.
    #[error("light w is {0}, but it must be 0 (directional) or positive (point, usually 1)")]
    NegativeW(f32),
    /// A directional light (w = 0) with a zero direction.
    #[error("a directional light (w = 0) needs a non-zero direction")]
    ZeroDirection,
    /// The text is not `X,Y,Z,W`.
    #[error("cannot parse light {text:?}: {why} (expected four numbers X,Y,Z,W, for example 0,10,0,1 for a point light or 1,1,0,0 for a directional light)")]
    Parse {
        /// The text given.
        text: String,
        /// What was wrong with it.
        why: String,
    },
}

/// A light in homogeneous coordinates `(x, y, z, w)`.
///
/// * A point light has `w = 1` and `xyz` is its position.
/// * A directional light has `w = 0` and `xyz` points *towards* the light (from the scene).
///
/// Any finite `w > 0` is accepted and means the point `xyz / w`; the predicates never divide, so
/// the sign results are exact for the `f32` values given. All components are finite by
/// construction.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "[f32; 4]", into = "[f32; 4]")]
pub struct Light(Vec4);

impl Light {
    /// Creates a light from its homogeneous components.
    ///
    /// # Errors
    /// [`LightError::NonFinite`] for NaN/Inf, [`LightError::NegativeW`] for `w < 0`,
    /// [`LightError::ZeroDirection`] for `(0, 0, 0, 0)`.
    pub fn new(x: f32, y: f32, z: f32, w: f32) -> Result<Self, LightError> {
        for (component, value) in [('x', x), ('y', y), ('z', z), ('w', w)] {
            if !value.is_finite() {
                return Err(LightError::NonFinite { component, value });
            }
        }
        if w < 0.0 {
            return Err(LightError::NegativeW(w));
        }
        if w == 0.0 && x == 0.0 && y == 0.0 && z == 0.0 {
            return Err(LightError::ZeroDirection);
        }
        Ok(Self(Vec4::new(x, y, z, w)))
    }

    /// A point light at `position` (`w = 1`).
    ///
    /// # Panics
    /// Panics if `position` is not finite.
    #[must_use]
    pub fn point(position: Vec3) -> Self {
        Self::new(position.x, position.y, position.z, 1.0).expect("point light must be finite")
    }

    /// A directional light; `towards` points from the scene towards the light (`w = 0`).
    ///
    /// # Panics
    /// Panics if `towards` is not finite or is zero.
    #[must_use]
    pub fn directional(towards: Vec3) -> Self {
        Self::new(towards.x, towards.y, towards.z, 0.0)
            .expect("directional light must be finite and non-zero")
    }

    /// The homogeneous vector `(x, y, z, w)`.
    #[must_use]
    pub fn to_vec4(self) -> Vec4 {
        self.0
    }

    /// The components as an array `[x, y, z, w]`.
    #[must_use]
    pub fn to_array(self) -> [f32; 4] {
        self.0.to_array()
    }

    /// True for `w = 0`.
    #[must_use]
    pub fn is_directional(self) -> bool {
        self.0.w == 0.0
    }
}

impl TryFrom<[f32; 4]> for Light {
    type Error = LightError;
    fn try_from(v: [f32; 4]) -> Result<Self, LightError> {
        Self::new(v[0], v[1], v[2], v[3])
    }
}

impl From<Light> for [f32; 4] {
    fn from(l: Light) -> Self {
        l.to_array()
    }
}

impl std::str::FromStr for Light {
    type Err = LightError;

    /// Parses `X,Y,Z,W` (four comma-separated numbers, spaces allowed).
    fn from_str(text: &str) -> Result<Self, LightError> {
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if parts.len() != 4 {
            return Err(LightError::Parse {
                text: text.to_owned(),
                why: format!("found {} component(s)", parts.len()),
            });
        }
        let mut v = [0f32; 4];
        for (i, p) in parts.iter().enumerate() {
            v[i] = p.parse::<f32>().map_err(|e| LightError::Parse {
                text: text.to_owned(),
                why: format!("component {} ({p:?}): {e}", i + 1),
            })?;
        }
        Self::try_from(v)
    }
}

impl std::fmt::Display for Light {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [x, y, z, w] = self.to_array();
        write!(f, "{x},{y},{z},{w}")
    }
}
