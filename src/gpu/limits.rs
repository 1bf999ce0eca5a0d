//! What an adapter's limits make of a paged array (`super::pages`): the page size and shift,
//! and the bind group covering a buffer page by page. Free functions of the limits (and the
//! device, to bind), so that `context` — which compiles each kernel for the page shift and
//! binds pages at dispatch — and `pages` — which gives `GpuContext` its public page arithmetic
//! — both build on them without depending on each other's code.

use crate::abi::PAGE_COUNT;

/// Every paged array is of 32-bit words.
pub(super) const WORD: u64 = 4;

/// Pages never pass 2 GiB: four of them then hold 2³¹ words, all a `u32` index can reach in
/// arrays whose indices are themselves words, and `PAGE_SHIFT` stays below 32.
const MAX_PAGE_BYTES: u64 = 1 << 31;

/// Bytes in one page: the largest power of two one storage binding (and one buffer) may hold,
/// and at least the offset alignment, so every page starts at a legal offset.
pub(super) fn page_bytes(limits: &wgpu::Limits) -> u64 {
    let limit = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
        .clamp(WORD, MAX_PAGE_BYTES);
    let largest = 1u64 << (63 - limit.leading_zeros());
    largest.max(limits.min_storage_buffer_offset_alignment as u64)
}

/// log2 of the words in a page, as the kernels' `PAGE_SHIFT`.
pub(super) fn page_shift(limits: &wgpu::Limits) -> u32 {
    (page_bytes(limits) / WORD).trailing_zeros()
}

/// Bind group `group` of `pipeline`: `buffer` page by page. Pages past the end of the buffer
/// bind its first page again (a binding must cover something; the kernel never reads them).
pub(super) fn page_bind_group(
    (device, limits): (&wgpu::Device, &wgpu::Limits),
    pipeline: &wgpu::ComputePipeline,
    group: u32,
    label: &str,
    buffer: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let page = page_bytes(limits);
    let size = buffer.size();
    let entries: Vec<wgpu::BindGroupEntry<'_>> = (0..PAGE_COUNT)
        .map(|k| {
            let start = if k * page < size { k * page } else { 0 };
            let length = page.min(size - start);
            wgpu::BindGroupEntry {
                binding: k as u32,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer,
                    offset: start,
                    size: wgpu::BufferSize::new(length),
                }),
            }
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &pipeline.get_bind_group_layout(group),
        entries: &entries,
    })
}
