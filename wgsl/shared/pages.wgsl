// Arrays too large for a single storage binding (src/gpu/pages.rs). A kernel imports this and
// declares each such array with a line `#paged NAME GROUP`, which src/gpu/shaders.rs expands
// from shared/paged_array.wgsl: bind group GROUP holds the array's four pages, page k words
// k << PAGE_SHIFT onwards, and `NAME(i)` reads word i. The host sets PAGE_SHIFT from the
// adapter's binding limit when it compiles the kernel; an array within one page has that page
// bound four times.

override PAGE_SHIFT: u32 = 29u;
