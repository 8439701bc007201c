//! Bookkeeping every backend shares: the store of prepared scenes behind [`PreparedId`]s, and
//! the light-list check of [`SilhouetteBackend::extract`](crate::SilhouetteBackend::extract).

use crate::{BackendError, Light, PreparedId};
use std::collections::HashMap;

/// The scenes a backend has prepared, keyed by the [`PreparedId`] that `prepare` returned, with
/// the backend's name for the errors about unknown ids.
///
/// Ids are allocated by [`insert`](Self::insert): each is one larger than the one before, so an
/// id is never reused, even after [`remove`](Self::remove).
///
/// ```
/// use shadowvol_silhouette::{BackendError, PreparedScenes};
///
/// let mut scenes = PreparedScenes::new("cpu");
/// let a = scenes.insert("scene a");
/// assert_eq!(scenes.get(a), Ok(&"scene a"));
/// assert_eq!(scenes.remove(a), Some("scene a"));
/// assert_eq!(scenes.get(a), Err(BackendError::UnknownScene { backend: "cpu", id: a }));
/// assert_ne!(scenes.insert("scene b"), a);
/// ```
#[derive(Debug, Clone)]
pub struct PreparedScenes<T> {
    backend: &'static str,
    scenes: HashMap<PreparedId, T>,
    next: u64,
}

impl<T> PreparedScenes<T> {
    /// An empty store of the backend named `backend`.
    #[must_use]
    pub fn new(backend: &'static str) -> Self {
        Self {
            backend,
            scenes: HashMap::new(),
            next: 0,
        }
    }

    /// The name of the backend the store belongs to.
    #[must_use]
    pub fn backend(&self) -> &'static str {
        self.backend
    }

    /// Stores `scene` under a fresh id and returns that id.
    pub fn insert(&mut self, scene: T) -> PreparedId {
        let id = PreparedId(self.next);
        self.next += 1;
        self.scenes.insert(id, scene);
        id
    }

    fn unknown(&self, id: PreparedId) -> BackendError {
        BackendError::UnknownScene {
            backend: self.backend,
            id,
        }
    }

    /// The scene stored under `id`.
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] naming the backend and `id` when no scene is stored under
    /// `id` (never returned by [`insert`](Self::insert), or removed since).
    pub fn get(&self, id: PreparedId) -> Result<&T, BackendError> {
        self.scenes.get(&id).ok_or_else(|| self.unknown(id))
    }

    /// The scene stored under `id`, mutably.
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] naming the backend and `id` when no scene is stored under
    /// `id`.
    pub fn get_mut(&mut self, id: PreparedId) -> Result<&mut T, BackendError> {
        let unknown = self.unknown(id);
        self.scenes.get_mut(&id).ok_or(unknown)
    }

    /// Removes and returns the scene stored under `id`, or `None` when there is none.
    pub fn remove(&mut self, id: PreparedId) -> Option<T> {
        self.scenes.remove(&id)
    }

    /// Removes and returns the scene stored under `id`, to be put back with
    /// [`restore`](Self::restore) (for backends that need the scene mutably and `&self` at once).
    ///
    /// # Errors
    /// [`BackendError::UnknownScene`] naming the backend and `id` when no scene is stored under
    /// `id`.
    pub fn take(&mut self, id: PreparedId) -> Result<T, BackendError> {
        let unknown = self.unknown(id);
        self.scenes.remove(&id).ok_or(unknown)
    }

    /// Puts back a scene taken out with [`take`](Self::take) or [`remove`](Self::remove) under
    /// the same `id`. Ids are not allocated here.
    ///
    /// # Panics
    /// In debug builds, when `id` was never allocated by [`insert`](Self::insert).
    pub fn restore(&mut self, id: PreparedId, scene: T) {
        debug_assert!(id.0 < self.next, "{id:?} was not allocated by this store");
        self.scenes.insert(id, scene);
    }

    /// Removes every scene, yielding each with its id (in no particular order). Ids already
    /// allocated are not reused.
    pub fn drain(&mut self) -> impl Iterator<Item = (PreparedId, T)> + '_ {
        self.scenes.drain()
    }

    /// Number of scenes stored.
    #[must_use]
    pub fn len(&self) -> usize {
        self.scenes.len()
    }

    /// Whether no scene is stored.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.scenes.is_empty()
    }
}

/// Checks the light list given to `extract`: it must not be empty.
///
/// # Errors
/// [`BackendError::InvalidInput`] with the message `"no lights given"` when `lights` is empty.
pub fn check_lights(lights: &[Light]) -> Result<(), BackendError> {
    if lights.is_empty() {
        return Err(BackendError::InvalidInput("no lights given".to_owned()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_start_at_zero_increase_and_are_never_reused() {
        let mut s = PreparedScenes::new("t");
        assert!(s.is_empty());
        assert_eq!(s.backend(), "t");
        let a = s.insert(10);
        let b = s.insert(20);
        assert_eq!((a, b), (PreparedId(0), PreparedId(1)));
        assert_eq!(s.len(), 2);
        *s.get_mut(b).unwrap() += 1;
        assert_eq!(s.get(b), Ok(&21));
        assert_eq!(s.remove(a), Some(10));
        assert_eq!(s.remove(a), None);
        assert_eq!(
            s.get(a),
            Err(BackendError::UnknownScene {
                backend: "t",
                id: a
            })
        );
        assert_eq!(
            s.get_mut(PreparedId(7)).unwrap_err().to_string(),
            "t backend: unknown prepared scene PreparedId(7)"
        );
        assert_eq!(s.insert(30), PreparedId(2));
        let v = s.take(b).unwrap();
        assert!(s.take(b).is_err());
        s.restore(b, v);
        assert_eq!(s.get(b), Ok(&21));
        let mut all: Vec<_> = s.drain().collect();
        all.sort_unstable();
        assert_eq!(all, vec![(PreparedId(1), 21), (PreparedId(2), 30)]);
        assert!(s.is_empty());
        assert_eq!(s.insert(40), PreparedId(3));
    }

    #[test]
    fn check_lights_rejects_only_an_empty_list() {
        assert_eq!(
            check_lights(&[]),
            Err(BackendError::InvalidInput("no lights given".to_owned()))
        );
        assert_eq!(check_lights(&[Light::point(glam::Vec3::ONE)]), Ok(()));
    }
}
