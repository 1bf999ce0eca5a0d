//! Growing the per-vertex and per-face arrays of a large mesh. `Vec` doubles its capacity
//! when full: a mesh of millions of faces that gains a few thousand by remeshing would then
//! hold twice the memory of each array, and copy it all at once in the middle of a stroke.
//! These grow by an eighth instead (still amortised O(1) per element).

/// A full array grows by its length over this…
const GROWTH_DIVISOR: usize = 8;
/// …and by at least this many elements.
const MIN_GROWTH: usize = 1024;

/// Makes room for `more` elements beyond `values.len()`.
pub fn room_for<T>(values: &mut Vec<T>, more: usize) {
    if values.len() + more > values.capacity() {
        values.reserve_exact((values.len() / GROWTH_DIVISOR).max(MIN_GROWTH) + more);
    }
}

/// Resizes `values` to at least `len`, filling with `fill`; never shrinks.
pub fn grow_to<T: Clone>(values: &mut Vec<T>, len: usize, fill: T) {
    if len > values.len() {
        room_for(values, len - values.len());
        values.resize(len, fill);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_full_array_grows_by_an_eighth_not_double() {
        let mut values = vec![0u32; 80_000];
        values.shrink_to_fit();
        room_for(&mut values, 1);
        assert!(values.capacity() >= 80_001);
        assert!(
            values.capacity() <= 80_000 + 10_001,
            "{}",
            values.capacity()
        );
        grow_to(&mut values, 80_005, 7);
        assert_eq!(values.len(), 80_005);
        assert_eq!(values[80_004], 7);
        // Never shrinks.
        grow_to(&mut values, 10, 0);
        assert_eq!(values.len(), 80_005);
    }
}
