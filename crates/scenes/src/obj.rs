//! OBJ loading.
