use std::time::Duration;

/// Per-edge multiplicities for every light of one `extract` call.
///
/// Values are stored light-major: `value(light, edge)`. Edge indices are *global*: the edges of
/// all objects of the prepared scene, concatenated in object order (see
/// [`crate::TopologyScene::edge_offsets`]). The compact silhouette list of a light holds the
/// global edge indices with `m != 0`, ascending.
///
/// It knows when every value outside the compact lists is 0 (after [`Multiplicities::reset`],
/// [`Multiplicities::rebuild_silhouettes`] or [`Multiplicities::mark_silhouettes_complete`],
/// until the values are handed out mutably), so that a backend may clear a reused result by
/// its listed values alone ([`Multiplicities::zero_listed`]).
#[derive(Debug, Clone, Default)]
pub struct Multiplicities {
    edges: usize,
    lights: usize,
    values: Vec<i32>,
    silhouettes: Vec<Vec<u32>>,
    /// Every value outside the compact lists is 0.
    zero_elsewhere: bool,
}

/// Equal shapes, values and compact lists (whether the lists are known to be complete is not
/// compared).
impl PartialEq for Multiplicities {
    fn eq(&self, other: &Self) -> bool {
        self.edges == other.edges
            && self.lights == other.lights
            && self.values == other.values
            && self.silhouettes == other.silhouettes
    }
}

impl Eq for Multiplicities {}

impl Multiplicities {
    /// All-zero multiplicities for `edges` edges and `lights` lights.
    #[must_use]
    pub fn zeroed(edges: usize, lights: usize) -> Self {
        let mut m = Self::default();
        m.reset(edges, lights);
        m
    }

    /// Resizes to `edges` × `lights` and zeroes everything, keeping allocations.
    pub fn reset(&mut self, edges: usize, lights: usize) {
        self.edges = edges;
        self.lights = lights;
        let n = edges * lights;
        if self.values.capacity() < n {
            // A fresh zeroed allocation: its pages stay the kernel's shared zero page until an
            // entry is written, so a result that is mostly zeros costs memory only around its
            // silhouette edges (and `resize` would write every zero).
            self.values = vec![0; n];
        } else {
            self.values.clear();
            self.values.resize(n, 0);
        }
        self.silhouettes.resize_with(lights, Vec::new);
        for s in &mut self.silhouettes {
            s.clear();
        }
        self.zero_elsewhere = true;
    }

    /// When the shape is `edges` × `lights` and every value outside the compact lists is known
    /// to be 0, sets the listed values to 0 and empties the lists, and returns true: every value
    /// is then 0, as after [`Multiplicities::reset`], for the cost of a silhouette rather than of
    /// every edge. Otherwise changes nothing and returns false.
    pub fn zero_listed(&mut self, edges: usize, lights: usize) -> bool {
        if !self.zero_elsewhere || self.edges != edges || self.lights != lights {
            return false;
        }
        for (l, s) in self.silhouettes.iter_mut().enumerate() {
            for &e in s.iter() {
                self.values[l * edges + e as usize] = 0;
            }
            s.clear();
        }
        true
    }

    /// Whether every value outside the compact lists is known to be 0 (see the type's
    /// documentation).
    #[must_use]
    pub fn zero_elsewhere(&self) -> bool {
        self.zero_elsewhere
    }

    /// Declares that the compact lists set with [`Multiplicities::set_silhouette`] list every
    /// value that is not 0, as a backend's do after an extraction (checked in debug builds).
    ///
    /// # Panics
    /// Debug builds panic when a list misses a non-zero value or names a zero one.
    pub fn mark_silhouettes_complete(&mut self) {
        debug_assert!(
            self.silhouettes_consistent(),
            "the compact lists do not list exactly the non-zero values"
        );
        self.zero_elsewhere = true;
    }

    /// Number of edges per light.
    #[must_use]
    pub fn edge_count(&self) -> usize {
        self.edges
    }

    /// Number of lights.
    #[must_use]
    pub fn light_count(&self) -> usize {
        self.lights
    }

    /// The multiplicities of all edges for `light`.
    ///
    /// # Panics
    /// Panics if `light >= self.light_count()`.
    #[must_use]
    pub fn values(&self, light: usize) -> &[i32] {
        &self.values[light * self.edges..(light + 1) * self.edges]
    }

    /// Mutable multiplicities of all edges for `light` (the lists are then no longer known to
    /// be complete).
    ///
    /// # Panics
    /// Panics if `light >= self.light_count()`.
    pub fn values_mut(&mut self, light: usize) -> &mut [i32] {
        self.zero_elsewhere = false;
        &mut self.values[light * self.edges..(light + 1) * self.edges]
    }

    /// All values, light-major (`light * edge_count + edge`).
    #[must_use]
    pub fn all_values(&self) -> &[i32] {
        &self.values
    }

    /// All values, mutable, light-major (the lists are then no longer known to be complete).
    pub fn all_values_mut(&mut self) -> &mut [i32] {
        self.zero_elsewhere = false;
        &mut self.values
    }

    /// The compact silhouette of `light`: global edge indices with `m != 0`, ascending.
    ///
    /// # Panics
    /// Panics if `light >= self.light_count()`.
    #[must_use]
    pub fn silhouette(&self, light: usize) -> &[u32] {
        &self.silhouettes[light]
    }

    /// Sets the compact silhouette of `light` from a backend-built list (any order; it is sorted).
    /// Once every list is set, [`Multiplicities::mark_silhouettes_complete`] declares them
    /// complete.
    ///
    /// # Panics
    /// Panics if `light >= self.light_count()`.
    pub fn set_silhouette(&mut self, light: usize, mut edges: Vec<u32>) {
        self.zero_elsewhere = false;
        edges.sort_unstable();
        self.silhouettes[light] = edges;
    }

    /// Rebuilds every compact silhouette list from the values.
    pub fn rebuild_silhouettes(&mut self) {
        for l in 0..self.lights {
            let vals = &self.values[l * self.edges..(l + 1) * self.edges];
            let s = &mut self.silhouettes[l];
            s.clear();
            s.extend(
                vals.iter()
                    .enumerate()
                    .filter(|(_, &m)| m != 0)
                    .map(|(e, _)| e as u32),
            );
        }
        self.zero_elsewhere = true;
    }

    /// Checks that each compact list lists exactly the edges with `m != 0`, ascending.
    #[must_use]
    pub fn silhouettes_consistent(&self) -> bool {
        (0..self.lights).all(|l| {
            let vals = self.values(l);
            let expected = vals.iter().filter(|&&m| m != 0).count();
            let s = &self.silhouettes[l];
            s.len() == expected
                && s.windows(2).all(|w| w[0] < w[1])
                && s.iter()
                    .all(|&e| vals.get(e as usize).is_some_and(|&m| m != 0))
        })
    }
}

/// Timings and counters of one `extract` call.
///
/// Times are wall-clock. On CPU backends `upload` and `readback` are zero.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExtractStats {
    /// Moving per-frame inputs (lights) to the device.
    pub upload: Duration,
    /// The computation itself (dispatch to completion).
    pub compute: Duration,
    /// Moving results back (multiplicities, compact lists, uncertain records).
    pub readback: Duration,
    /// Host time spent deciding uncertain (edge, OV) pairs exactly.
    pub host_resolve: Duration,
    /// Number of (edge, OV, light) evaluations the device filter could not certify and the host
    /// decided with the exact predicate (exact mode only; 0 otherwise).
    pub uncertain: u64,
}

impl ExtractStats {
    /// Total of all times.
    #[must_use]
    pub fn total(&self) -> Duration {
        self.upload + self.compute + self.readback + self.host_resolve
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listed_values_clear_a_result_known_to_be_zero_elsewhere() {
        let mut m = Multiplicities::zeroed(5, 2);
        assert!(m.zero_elsewhere());
        m.values_mut(1)[3] = -2;
        assert!(!m.zero_elsewhere());
        // Not known: nothing is cleared.
        assert!(!m.zero_listed(5, 2));
        assert_eq!(m.values(1)[3], -2);
        m.rebuild_silhouettes();
        assert!(m.zero_elsewhere());
        assert_eq!(m.silhouette(1), &[3]);
        // Another shape: nothing is cleared.
        assert!(!m.zero_listed(5, 3));
        assert!(m.zero_listed(5, 2));
        assert_eq!(m, Multiplicities::zeroed(5, 2));
        // A backend's lists, declared complete.
        m.all_values_mut()[2] = 1;
        m.set_silhouette(0, vec![2]);
        assert!(!m.zero_elsewhere());
        m.mark_silhouettes_complete();
        assert!(m.zero_listed(5, 2));
        assert!(m.all_values().iter().all(|&v| v == 0));
        assert!(m.silhouettes_consistent());
    }
}
