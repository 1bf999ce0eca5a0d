// Template of `#paged NAME GROUP` (see shared/pages.wgsl): PAGED is replaced by NAME and
// PAGE_GROUP by GROUP. Not imported directly.
@group(PAGE_GROUP) @binding(0) var<storage, read> PAGED_page_0: array<u32>;
@group(PAGE_GROUP) @binding(1) var<storage, read> PAGED_page_1: array<u32>;
@group(PAGE_GROUP) @binding(2) var<storage, read> PAGED_page_2: array<u32>;
@group(PAGE_GROUP) @binding(3) var<storage, read> PAGED_page_3: array<u32>;

// Word i of the paged array. One exit (see shared/geom.wgsl on lavapipe and early returns).
fn PAGED(i: u32) -> u32 {
    let at = i & ((1u << PAGE_SHIFT) - 1u);
    var word = 0u;
    switch i >> PAGE_SHIFT {
        case 0u: {
            word = PAGED_page_0[at];
        }
        case 1u: {
            word = PAGED_page_1[at];
        }
        case 2u: {
            word = PAGED_page_2[at];
        }
        default: {
            word = PAGED_page_3[at];
        }
    }
    return word;
}
