//! A map from a table's indices back to the input's: the identity unless stored.

/// A strictly increasing map from a table's indices to the input's, such as
/// [`EdgeTable::vertex_names`](crate::EdgeTable::vertex_names) (compact vertex id → input index)
/// and [`EdgeTable::triangle_sources`](crate::EdgeTable::triangle_sources) (kept triangle →
/// input triangle).
///
/// A mesh with nothing to weld and no degenerate triangle maps every index to itself; then
/// nothing is stored ([`Renumbering::Identity`]), which saves 6 bytes a triangle on a closed
/// mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Renumbering {
    /// `i → i` for `i` below the length.
    Identity(usize),
    /// `i → map[i]`; strictly increasing.
    Stored(Vec<u32>),
}

impl Default for Renumbering {
    fn default() -> Self {
        Self::Identity(0)
    }
}

impl Renumbering {
    /// `map`, or [`Renumbering::Identity`] of its length when `map[i] == i` everywhere (the
    /// vector is then freed).
    #[must_use]
    pub fn from_vec(map: Vec<u32>) -> Self {
        if map.iter().enumerate().all(|(i, &v)| v as usize == i) {
            Self::Identity(map.len())
        } else {
            Self::Stored(map)
        }
    }

    /// The input index of `i`.
    ///
    /// # Panics
    /// If `i >= self.len()`.
    #[must_use]
    #[inline]
    pub fn get(&self, i: usize) -> u32 {
        match self {
            Self::Identity(n) => {
                assert!(i < *n, "index {i} out of range of a renumbering of {n}");
                i as u32
            }
            Self::Stored(map) => map[i],
        }
    }

    /// Number of indices mapped.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Self::Identity(n) => *n,
            Self::Stored(map) => map.len(),
        }
    }

    /// True when no index is mapped.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// True when nothing is stored (every index maps to itself).
    #[must_use]
    pub fn is_identity(&self) -> bool {
        matches!(self, Self::Identity(_))
    }

    /// The input indices in order.
    pub fn iter(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }

    /// The input indices as a vector (4 bytes an index, allocated on each call).
    #[must_use]
    pub fn to_vec(&self) -> Vec<u32> {
        self.iter().collect()
    }

    /// The index whose input index is `value`, if any (a binary search: the map is increasing).
    #[must_use]
    pub fn position(&self, value: u32) -> Option<usize> {
        match self {
            Self::Identity(n) => ((value as usize) < *n).then_some(value as usize),
            Self::Stored(map) => map.binary_search(&value).ok(),
        }
    }

    /// Applies `f` to every input index, storing the result unless it is the identity again.
    #[must_use]
    pub fn map(self, f: impl Fn(u32) -> u32) -> Self {
        Self::from_vec(self.iter().map(f).collect())
    }

    /// Heap bytes held: 4 an index when stored, none for the identity.
    #[must_use]
    pub fn heap_bytes(&self) -> u64 {
        match self {
            Self::Identity(_) => 0,
            Self::Stored(map) => crate::vec_bytes(map),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_is_not_stored_and_answers_like_the_vector() {
        let id = Renumbering::from_vec(vec![0, 1, 2]);
        assert_eq!(id, Renumbering::Identity(3));
        assert_eq!(id.heap_bytes(), 0);
        assert_eq!(id.to_vec(), vec![0, 1, 2]);
        assert_eq!(id.position(2), Some(2));
        assert_eq!(id.position(3), None);
        let stored = Renumbering::from_vec(vec![0, 2, 5]);
        assert!(!stored.is_identity());
        assert_eq!((stored.get(1), stored.len()), (2, 3));
        assert_eq!(stored.position(5), Some(2));
        assert_eq!(stored.position(1), None);
        assert_eq!(stored.heap_bytes(), 12);
    }

    #[test]
    #[should_panic(expected = "out of range")]
    fn identity_panics_out_of_range_like_a_vector() {
        let _ = Renumbering::Identity(2).get(2);
    }
}
