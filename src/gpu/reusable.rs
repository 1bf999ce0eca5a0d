//! Buffers a backend keeps from step to step: grown (to the next power of two) when a step
//! needs more, never shrunk, so that steady sculpting allocates nothing on the GPU. Creating
//! buffers every step was the largest cost of the first GPU backend on lavapipe.

use bytemuck::Pod;

use super::{GpuContext, GpuError};

pub struct ReusableBuffer {
    label: &'static str,
    usage: wgpu::BufferUsages,
    /// Bound page by page (`super::pages`) rather than whole.
    paged: bool,
    buffer: Option<wgpu::Buffer>,
}

impl ReusableBuffer {
    /// A storage buffer the host writes and copies from.
    pub fn storage(label: &'static str) -> ReusableBuffer {
        ReusableBuffer::with_usage(
            label,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        )
    }

    /// A storage buffer of `u32` words that kernels bind page by page (`super::pages`).
    pub fn paged(label: &'static str) -> ReusableBuffer {
        ReusableBuffer {
            paged: true,
            ..ReusableBuffer::storage(label)
        }
    }

    /// A buffer the host maps to read results back.
    pub fn readback(label: &'static str) -> ReusableBuffer {
        ReusableBuffer::with_usage(
            label,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        )
    }

    fn with_usage(label: &'static str, usage: wgpu::BufferUsages) -> ReusableBuffer {
        ReusableBuffer {
            label,
            usage,
            paged: false,
            buffer: None,
        }
    }

    /// Makes room for `bytes` (at least 4, so that empty steps stay legal); the contents are
    /// undefined after growing. Fails clearly past one binding's limit.
    pub fn reserve(&mut self, gpu: &GpuContext, bytes: u64) -> Result<(), GpuError> {
        let bytes = bytes.max(4);
        if self.buffer.as_ref().is_some_and(|b| b.size() >= bytes) {
            return Ok(());
        }
        let mut limit = gpu.limits.max_buffer_size;
        if self.paged {
            gpu.check_paged(self.label, bytes.div_ceil(4) as usize)?;
        } else if self.usage.contains(wgpu::BufferUsages::STORAGE) {
            gpu.check_binding::<u8>(self.label, bytes as usize)?;
            // It is bound whole: rounding up must not pass a binding's limit either.
            limit = limit.min(gpu.limits.max_storage_buffer_binding_size);
        }
        let size = bytes
            .next_power_of_two()
            .min(limit & !3)
            .max(bytes)
            .div_ceil(4)
            * 4;
        self.buffer = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(self.label),
            size,
            usage: self.usage,
            mapped_at_creation: false,
        }));
        Ok(())
    }

    /// Makes room for `data` and queues its upload (done before the next submission).
    pub fn upload<T: Pod>(&mut self, gpu: &GpuContext, data: &[T]) -> Result<(), GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        self.reserve(gpu, bytes.len() as u64)?;
        if !bytes.is_empty() {
            gpu.queue.write_buffer(self.buffer(), 0, bytes);
        }
        Ok(())
    }

    /// Submits `encoder` with copies of the first bytes of each part (multiples of 4) one
    /// after another into this (read-back) buffer, and reads them back in one map: one
    /// blocking round trip however many buffers the CPU needs from the submission.
    pub fn read_back_parts(
        &mut self,
        gpu: &GpuContext,
        mut encoder: wgpu::CommandEncoder,
        parts: &[(&wgpu::Buffer, u64)],
    ) -> Result<Vec<u8>, GpuError> {
        let total: u64 = parts.iter().map(|&(_, bytes)| bytes).sum();
        self.reserve(gpu, total)?;
        self.record_copies(&mut encoder, parts, 0);
        self.submit_and_map(gpu, encoder, total)
    }

    /// Records copies of the first bytes of each part one after another into this buffer from
    /// byte `at`, and returns where they end: the parts as they are at this point of the
    /// encoder, which may overwrite them after.
    pub fn record_copies(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        parts: &[(&wgpu::Buffer, u64)],
        mut at: u64,
    ) -> u64 {
        for &(source, bytes) in parts {
            encoder.copy_buffer_to_buffer(source, 0, self.buffer(), at, bytes);
            at += bytes;
        }
        at
    }

    /// Submits `encoder`, which copied `total` bytes into this (read-back) buffer, and maps them.
    pub fn submit_and_map(
        &self,
        gpu: &GpuContext,
        encoder: wgpu::CommandEncoder,
        total: u64,
    ) -> Result<Vec<u8>, GpuError> {
        gpu.submit(encoder);
        let mut data = gpu.map_read(self.buffer())?;
        data.truncate(total as usize);
        Ok(data)
    }

    /// The buffer; [`ReusableBuffer::reserve`] or [`ReusableBuffer::upload`] first.
    pub fn buffer(&self) -> &wgpu::Buffer {
        self.buffer
            .as_ref()
            .expect("reserve a reusable buffer before using it")
    }
}

/// Uploads the rows of `data` listed in `rows` into `buffer`, one copy per run of consecutive
/// rows: a step's moved vertices, listed in ascending order, are a few runs of the vertex order.
/// Unsorted rows are uploaded all the same, in more copies.
pub fn upload_rows<T: Pod>(gpu: &GpuContext, buffer: &wgpu::Buffer, data: &[T], rows: &[u32]) {
    let mut patches = Patches::default();
    patches.rows(buffer, data, rows);
    patches.submit(gpu);
}

/// Writes into GPU buffers gathered into one upload: one staging buffer holding every piece,
/// and one copy per piece, submitted together. Remeshing rewrites a few thousand scattered rows
/// a stroke; a `write_buffer` each costs a staging allocation each.
#[derive(Default)]
pub struct Patches<'a> {
    bytes: Vec<u8>,
    /// Destination, offset there, and the piece's range in `bytes`.
    pieces: Vec<(&'a wgpu::Buffer, u64, std::ops::Range<usize>)>,
}

impl<'a> Patches<'a> {
    /// Queues `data` for `buffer` at element `index` (elements of `T`). Runs that continue the
    /// last piece join it.
    pub fn write<T: Pod>(&mut self, buffer: &'a wgpu::Buffer, index: usize, data: &[T]) {
        let size = std::mem::size_of::<T>() as u64;
        let piece: &[u8] = bytemuck::cast_slice(data);
        if piece.is_empty() {
            return;
        }
        let offset = index as u64 * size;
        let start = self.bytes.len();
        self.bytes.extend_from_slice(piece);
        if let Some((last, at, range)) = self.pieces.last_mut()
            && std::ptr::eq(*last, buffer)
            && *at + range.len() as u64 == offset
        {
            range.end = self.bytes.len();
            return;
        }
        self.pieces.push((buffer, offset, start..self.bytes.len()));
    }

    /// Queues the rows of `data` listed in `rows` (ascending rows make few pieces).
    pub fn rows<T: Pod>(&mut self, buffer: &'a wgpu::Buffer, data: &[T], rows: &[u32]) {
        for &row in rows {
            let row = row as usize;
            self.write(buffer, row, &data[row..row + 1]);
        }
    }

    /// Uploads everything queued, ahead of any later submission.
    pub fn submit(self, gpu: &GpuContext) {
        if self.pieces.is_empty() {
            return;
        }
        use wgpu::util::DeviceExt;
        let staging = gpu
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("patches"),
                contents: &self.bytes,
                usage: wgpu::BufferUsages::COPY_SRC,
            });
        let mut encoder = gpu.encoder("patches");
        for (buffer, offset, range) in &self.pieces {
            encoder.copy_buffer_to_buffer(
                &staging,
                range.start as u64,
                buffer,
                *offset,
                range.len() as u64,
            );
        }
        gpu.submit(encoder);
    }
}
