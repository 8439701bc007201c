//! The egui overlay: the frame's figures and the controls' state.

use crate::controls::{self, VolumeView};
use shadowvol_renderer::{Frame, Pipeline, PlanPolicy, Technique};

/// What the overlay shows.
pub(crate) struct Stats {
    fps: f64,
    frame_ms: f64,
    mode: String,
    adapter: String,
    edges: usize,
    uncertain: u64,
    host_resolved: u64,
    pipeline: Pipeline,
    policy: PlanPolicy,
    volumes: VolumeView,
    techniques: Vec<String>,
    /// Per light: radius and samples.
    soft: Vec<(f32, u32)>,
}

impl Stats {
    /// The figures of `frame`, the frame times so far, and the viewer's settings.
    pub(crate) fn of(
        frame: &Frame,
        times: &[f64],
        policy: PlanPolicy,
        volumes: VolumeView,
    ) -> Self {
        let recent = &times[times.len().saturating_sub(30)..];
        let mean = if recent.is_empty() {
            0.0
        } else {
            recent.iter().sum::<f64>() / recent.len() as f64
        };
        Self {
            fps: if mean > 0.0 { 1e3 / mean } else { 0.0 },
            frame_ms: mean,
            mode: frame.report.mode.to_string(),
            adapter: frame.report.adapter.clone(),
            edges: frame.report.plan.iter().map(|e| e.silhouette_edges).sum(),
            uncertain: frame.report.uncertain,
            host_resolved: frame.report.host_resolved,
            pipeline: frame.report.pipeline,
            policy,
            volumes,
            soft: frame
                .report
                .light_radii
                .iter()
                .zip(&frame.report.samples)
                .map(|(&r, c)| (r, c.samples))
                .collect(),
            techniques: frame
                .report
                .plan
                .iter()
                .filter(|e| e.reason != "receiver only: casts no shadow")
                .map(|e| {
                    let t = match e.technique {
                        Technique::Culled => "culled",
                        Technique::ZPass => "z-pass",
                        Technique::ZFail => "z-fail",
                    };
                    format!("light {} · {}: {t}", e.light, e.object_name)
                })
                .collect(),
        }
    }

    /// Draws the overlay window.
    pub(crate) fn show(&self, ui: &mut egui::Ui) {
        egui::Window::new("shadowvol")
            .default_pos([6.0, 6.0])
            .resizable(false)
            .collapsible(true)
            .show(ui.ctx(), |ui| {
                let line = |ui: &mut egui::Ui, t: String| {
                    ui.label(egui::RichText::new(t).small());
                };
                line(
                    ui,
                    format!("{:.1} fps · {:.2} ms/frame", self.fps, self.frame_ms),
                );
                line(
                    ui,
                    format!(
                        "mode {} (1-4) · technique {} (T) · volumes {} (V)",
                        self.mode,
                        controls::policy_name(self.policy),
                        self.volumes.name()
                    ),
                );
                line(
                    ui,
                    format!(
                        "silhouette edges {} · uncertain pairs {} · host-resolved {} · {} pipeline",
                        self.edges,
                        self.uncertain,
                        self.host_resolved,
                        self.pipeline.name()
                    ),
                );
                let sizes: Vec<String> = self
                    .soft
                    .iter()
                    .map(|(r, n)| format!("{r:.3} ({n} sample{})", if *n == 1 { "" } else { "s" }))
                    .collect();
                line(
                    ui,
                    format!(
                        "light radius {} ([ and ] halve and double)",
                        sizes.join(", ")
                    ),
                );
                for t in self.techniques.iter().take(6) {
                    line(ui, t.clone());
                }
                if self.techniques.len() > 6 {
                    line(ui, format!("… {} more", self.techniques.len() - 6));
                }
                line(ui, self.adapter.clone());
            });
    }
}
