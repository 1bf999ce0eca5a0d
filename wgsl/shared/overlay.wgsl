// The overlay table as the kernels that refile it on the GPU share it (src/gpu/overlay.rs):
// `overlay_members` → `overlay_keys` → `cell_counts`, `scan`, `scatter` → `overlay_entries`.
// Members sit in slots: `members[slot]` is a vertex id, `marks[v]` is the vertex's slot + 1
// (0 for a vertex the overlay does not hold), and one word counts the slots taken.

// Host struct: `OverlayParams`.
struct OverlayParams {
    // Invocations: slots of the moving list (`overlay_members`), of the member list (the
    // others).
    count: u32,
    // Slots the member list has room for.
    room: u32,
    // Overlay table size minus one (a power of two).
    table_mask: u32,
    inv_cell_size: f32,
}
