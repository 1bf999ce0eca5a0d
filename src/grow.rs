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

/// `len` copies of `fill`, with the room of a first growth already reserved: an array of a
/// mesh that remeshing is about to grow then grows in place instead of copying itself in the
/// middle of the first stroke.
pub fn filled_with_room<T: Clone>(len: usize, fill: T) -> Vec<T> {
    let mut values = Vec::with_capacity(len + (len / GROWTH_DIVISOR).max(MIN_GROWTH));
    values.resize(len, fill);
    values
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
        // Room for a first growth up front: it grows in place.
        let mut values = filled_with_room(80_000, 3u32);
        let (before, capacity) = (values.as_ptr(), values.capacity());
        assert!(capacity >= 90_000, "{capacity}");
        grow_to(&mut values, 85_000, 7);
        assert_eq!((values.as_ptr(), values.capacity()), (before, capacity));
        assert_eq!((values[79_999], values[84_999]), (3, 7));
    }
}
