//! wgpu errors as values: the scopes the backend and the renderer push around their calls.

/// Out-of-memory, validation and internal error scopes around a block of wgpu calls: what the
/// block raises comes back from [`ErrorScopes::pop`] as text instead of reaching the device's
/// uncaptured-error handler (whose default panics). Internal errors include a shader the
/// backend's compiler rejects (OpenGL's limits on samplers, for example).
#[must_use = "pop the scopes to learn what the block raised"]
pub struct ErrorScopes {
    scopes: Vec<wgpu::ErrorScopeGuard>,
}

impl ErrorScopes {
    /// Pushes the three scopes on `device`.
    pub fn push(device: &wgpu::Device) -> Self {
        Self {
            scopes: vec![
                device.push_error_scope(wgpu::ErrorFilter::OutOfMemory),
                device.push_error_scope(wgpu::ErrorFilter::Validation),
                device.push_error_scope(wgpu::ErrorFilter::Internal),
            ],
        }
    }

    /// Pops the scopes (innermost first) and returns the captured errors, `; `-separated, each
    /// with wgpu's description (which names the call, the object and the rule), or `None`.
    #[must_use]
    pub fn pop(mut self) -> Option<String> {
        let mut errors = Vec::new();
        while let Some(scope) = self.scopes.pop() {
            if let Some(e) = pollster::block_on(scope.pop()) {
                errors.push(match &e {
                    wgpu::Error::OutOfMemory { .. } => "out of device memory".to_owned(),
                    wgpu::Error::Validation { description, .. } => {
                        format!("validation: {}", description.trim())
                    }
                    wgpu::Error::Internal { description, .. } => {
                        format!("internal error: {}", description.trim())
                    }
                });
            }
        }
        (!errors.is_empty()).then(|| errors.join("; "))
    }
}
