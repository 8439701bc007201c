//! The plan's lines as a report states them: per (light, object), the technique, why, and
//! what was drawn.

use serde::{Deserialize, Serialize};

/// How one (light, object) pair is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Technique {
    /// Not drawn: its shadow volume cannot reach the view.
    Culled,
    /// Depth-pass counting, sides only.
    ZPass,
    /// Depth-fail counting, sides plus front cap (and back cap for point lights).
    ZFail,
}

impl Technique {
    /// `culled`, `z-pass`, `z-fail`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Technique::Culled => "culled",
            Technique::ZPass => "z-pass",
            Technique::ZFail => "z-fail",
        }
    }
}

/// Where a (light, object)'s silhouette came from this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SilhouetteSource {
    /// Computed by the backend this frame.
    Extracted,
    /// Last frame's, because neither the light nor the object moved (nor mesh or mode changed).
    Reused,
    /// Not needed (culled).
    Skipped,
}

/// One line of the plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanEntry {
    /// Light index.
    pub light: usize,
    /// Object index.
    pub object: usize,
    /// Object name.
    pub object_name: String,
    /// The technique chosen.
    pub technique: Technique,
    /// True when a back cap is drawn (z-fail with a point light).
    pub back_cap: bool,
    /// Where the silhouette came from.
    pub silhouette: SilhouetteSource,
    /// Silhouette edges (m != 0).
    pub silhouette_edges: usize,
    /// Side quads drawn (`Σ |m|`; directional lights: triangles).
    pub side_quads: usize,
    /// Cap triangles drawn (front plus back).
    pub cap_triangles: usize,
    /// Why this technique, in words.
    pub reason: String,
    /// The light's scissor rectangle `[x, y, width, height]` in pixels (top-left origin), which
    /// limits its stencil and lit passes; `None`: the whole image. The same for every object of
    /// a light.
    pub scissor: Option<[u32; 4]>,
}

impl std::fmt::Display for PlanEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "light {} x object {} ({}): {}{}; silhouette {}; {} edges, {} side quads, {} cap triangles; {}",
            self.light,
            self.object,
            self.object_name,
            self.technique.name(),
            if self.technique == Technique::ZFail {
                if self.back_cap {
                    " with front and back caps"
                } else {
                    " with front cap only (directional light)"
                }
            } else {
                ""
            },
            match self.silhouette {
                SilhouetteSource::Extracted => "extracted",
                SilhouetteSource::Reused => "reused from last frame",
                SilhouetteSource::Skipped => "skipped",
            },
            self.silhouette_edges,
            self.side_quads,
            self.cap_triangles,
            self.reason
        )
    }
}
