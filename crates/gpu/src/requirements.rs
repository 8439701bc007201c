//! What the kernels need of a device: the limits and capabilities to check before building
//! them, the limits to request when opening a device, and the features they use where the
//! adapter has them. One place for the `wgpu` backend and the renderer's passes.

use crate::shaders::WORKGROUP_SIZE;

/// What one set of kernels needs of a device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Needs {
    /// Who needs it, for messages ("the kernels", "the GPU pipeline").
    pub who: &'static str,
    /// Storage buffers bound in one shader stage.
    pub storage_buffers: u32,
    /// Threads per workgroup (`WORKGROUP_SIZE` of the kernels).
    pub workgroup_size: u32,
    /// Downlevel capabilities, each with its name for messages.
    pub downlevel: &'static [(wgpu::DownlevelFlags, &'static str)],
}

/// The silhouette kernels of `shaders/silhouette.wgsl` as the `wgpu` backend binds them: the
/// packed tables, lights, multiplicities, counters, compact lists, uncertain pairs and signs
/// (within `wgpu::Limits::default()`'s 8).
pub const SILHOUETTE: Needs = Needs {
    who: "the kernels",
    storage_buffers: 7,
    workgroup_size: WORKGROUP_SIZE,
    downlevel: &[(wgpu::DownlevelFlags::COMPUTE_SHADERS, "COMPUTE_SHADERS")],
};

/// The renderer's GPU-resident pass: the silhouette kernels' functions in its own triangle and
/// edge passes, storage buffers read by vertex shaders, indirect draws. Its most in one stage:
/// the compute pipeline that writes the pending dispatch's arguments (the packed tables,
/// lights, signs, techniques, indirect arguments, side records and the pending arguments: 7);
/// the side and cap draws bind 6 in the vertex stage, none in the fragment stage.
pub const RESIDENT: Needs = Needs {
    who: "the GPU pipeline",
    storage_buffers: 7,
    workgroup_size: WORKGROUP_SIZE,
    downlevel: &[
        (
            wgpu::DownlevelFlags::VERTEX_STORAGE,
            "VERTEX_STORAGE (storage buffers in vertex shaders)",
        ),
        (
            wgpu::DownlevelFlags::INDIRECT_EXECUTION,
            "INDIRECT_EXECUTION (indirect draws)",
        ),
        (wgpu::DownlevelFlags::COMPUTE_SHADERS, "COMPUTE_SHADERS"),
    ],
};

impl Needs {
    /// `Err` naming the first limit of `l` below what the kernels need.
    ///
    /// # Errors
    /// The storage buffers per stage or the invocations per workgroup, with both figures.
    pub fn check_limits(&self, l: &wgpu::Limits) -> Result<(), String> {
        if l.max_storage_buffers_per_shader_stage < self.storage_buffers {
            return Err(format!(
                "max_storage_buffers_per_shader_stage is {}; {} need {}",
                l.max_storage_buffers_per_shader_stage, self.who, self.storage_buffers
            ));
        }
        if l.max_compute_invocations_per_workgroup < self.workgroup_size
            || l.max_compute_workgroup_size_x < self.workgroup_size
        {
            return Err(format!(
                "the device allows {} invocations per workgroup; {} need {}",
                l.max_compute_invocations_per_workgroup, self.who, self.workgroup_size
            ));
        }
        Ok(())
    }

    /// `Err` naming the first downlevel capability or limit `adapter` lacks.
    ///
    /// # Errors
    /// As above.
    pub fn check_adapter(&self, adapter: &wgpu::Adapter) -> Result<(), String> {
        let flags = adapter.get_downlevel_capabilities().flags;
        if let Some((_, name)) = self.downlevel.iter().find(|(f, _)| !flags.contains(*f)) {
            return Err(format!(
                "the adapter lacks the downlevel capability {name}, which {} need",
                self.who
            ));
        }
        self.check_limits(&adapter.limits())
    }

    /// Limits to request on a device of `adapter`: the downlevel defaults at the adapter's
    /// resolution, with the adapter's storage buffer counts, binding and buffer sizes (each at
    /// most `cap` bytes where given) and workgroups per dimension.
    ///
    /// # Errors
    /// As [`Needs::check_adapter`].
    pub fn limits(
        &self,
        adapter: &wgpu::Adapter,
        cap: Option<u64>,
    ) -> Result<wgpu::Limits, String> {
        self.check_adapter(adapter)?;
        let a = adapter.limits();
        let cap = cap.unwrap_or(u64::MAX);
        let mut l = wgpu::Limits::downlevel_defaults().using_resolution(a.clone());
        l.max_storage_buffers_per_shader_stage = a.max_storage_buffers_per_shader_stage;
        l.max_storage_buffer_binding_size = a.max_storage_buffer_binding_size.min(cap);
        l.max_buffer_size = a.max_buffer_size.min(cap);
        l.max_compute_workgroups_per_dimension = a.max_compute_workgroups_per_dimension;
        Ok(l)
    }
}

/// Features the passes use when the adapter has them: `DEPTH_CLIP_CONTROL` (depth clamp for
/// z-fail volumes), `SHADER_F64` (the `f64` exact filter) and `TIMESTAMP_QUERY` (GPU times).
#[must_use]
pub fn optional_features(adapter: &wgpu::Adapter) -> wgpu::Features {
    adapter.features()
        & (wgpu::Features::DEPTH_CLIP_CONTROL
            | wgpu::Features::SHADER_F64
            | wgpu::Features::TIMESTAMP_QUERY)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_below_the_needs_are_named() {
        // WebGPU's guaranteed limits are enough for both.
        let mut l = wgpu::Limits::default();
        assert_eq!(l.max_storage_buffers_per_shader_stage, 8);
        assert_eq!(RESIDENT.check_limits(&l), Ok(()));
        assert_eq!(SILHOUETTE.check_limits(&l), Ok(()));
        l.max_storage_buffers_per_shader_stage = 6;
        let e = RESIDENT.check_limits(&l).unwrap_err();
        assert!(
            e.contains("max_storage_buffers_per_shader_stage is 6")
                && e.contains("the GPU pipeline need 7"),
            "{e}"
        );
        let e = SILHOUETTE.check_limits(&l).unwrap_err();
        assert!(e.contains("the kernels need 7"), "{e}");
        l.max_storage_buffers_per_shader_stage = 7;
        assert_eq!(SILHOUETTE.check_limits(&l), Ok(()));
        l.max_compute_invocations_per_workgroup = 64;
        let e = SILHOUETTE.check_limits(&l).unwrap_err();
        assert!(e.contains("64") && e.contains("256"), "{e}");
    }
}
