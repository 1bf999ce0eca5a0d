//! The viewport's GPU side: the mesh's render rows in one storage buffer (indexed by vertex
//! number, so a stroke's changed vertices are written in place), the live faces' corners in
//! another, drawn with the preview renderer's shader (`wgsl/render/preview.wgsl`) into a
//! texture the app owns and egui shows. It renders only when the camera, the options or the
//! mesh changed.

use eframe::{egui, egui_wgpu};

use super::upload::MeshUpdate;
use crate::gpu::GpuError;
use crate::render::{
    Camera, MSAA_SAMPLES, PreviewTargets, PreviewUniforms, RenderOptions, RenderVertex,
    preview_bind_group, preview_pipeline, preview_uniforms, record_preview_draws,
};

/// What the user toggles in the view.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ViewOptions {
    pub wireframe: bool,
    pub false_colour: bool,
    pub show_mask: bool,
    /// Bit `l`: layer `l` hidden.
    pub hidden_layers: u32,
}

pub struct Viewport {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    vertices: wgpu::Buffer,
    corners: wgpu::Buffer,
    corner_count: u32,
    bind_group: wgpu::BindGroup,
    targets: Option<PreviewTargets>,
    /// The texture egui shows.
    pub texture: Option<egui::TextureId>,
    /// Something changed since the last render.
    pub dirty: bool,
    /// Bytes written to GPU buffers since [`Viewport::take_uploaded`] last ran.
    uploaded: u64,
    /// What the last render drew with: a camera or view change differs from it.
    drawn_with: Option<PreviewUniforms>,
    samples: u32,
}

impl Viewport {
    /// `antialias`: 4 samples a pixel (costly on a software rasterizer: lavapipe draws a
    /// 1280×800 viewport ~2× faster without).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        antialias: bool,
    ) -> Result<Viewport, GpuError> {
        let samples = if antialias { MSAA_SAMPLES } else { 1 };
        let pipeline = preview_pipeline(device, samples)?;
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewport uniforms"),
            size: std::mem::size_of::<PreviewUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let vertices = storage(device, "viewport vertices", 64);
        let corners = storage(device, "viewport corners", 64);
        let bind_group = bind(device, &pipeline, &uniform, &vertices, &corners);
        Ok(Viewport {
            device: device.clone(),
            queue: queue.clone(),
            pipeline,
            uniform,
            vertices,
            corners,
            corner_count: 0,
            bind_group,
            targets: None,
            texture: None,
            dirty: true,
            uploaded: 0,
            drawn_with: None,
            samples,
        })
    }

    /// Writes what the engine changed into the buffers, growing them (contents kept) when
    /// the mesh grew. A mesh too large for one storage binding of this adapter is refused with
    /// the reason (the viewport then draws nothing; the engine is unaffected).
    pub fn apply(&mut self, update: &MeshUpdate) -> Result<(), String> {
        let row = std::mem::size_of::<RenderVertex>() as u64;
        let corner = 12u64;
        let (vertex_bytes, corner_bytes) = (
            update.vertex_count as u64 * row,
            update.face_count as u64 * corner,
        );
        let limit = self.binding_limit();
        if vertex_bytes.max(corner_bytes) > limit {
            self.corner_count = 0;
            self.dirty = true;
            return Err(format!(
                "the viewport cannot draw {} vertices: {} MiB of vertex rows, over this adapter's storage binding limit of {} MiB",
                update.vertex_count,
                vertex_bytes.max(corner_bytes) >> 20,
                limit >> 20
            ));
        }
        let grown_vertices = self.grown(&self.vertices, "viewport vertices", vertex_bytes);
        let grown_corners = self.grown(&self.corners, "viewport corners", corner_bytes);
        if grown_vertices.is_some() || grown_corners.is_some() {
            self.vertices = grown_vertices.unwrap_or_else(|| self.vertices.clone());
            self.corners = grown_corners.unwrap_or_else(|| self.corners.clone());
            self.bind_group = bind(
                &self.device,
                &self.pipeline,
                &self.uniform,
                &self.vertices,
                &self.corners,
            );
        }
        for (first, rows) in &update.rows {
            let bytes: &[u8] = bytemuck::cast_slice(rows);
            self.queue
                .write_buffer(&self.vertices, *first as u64 * row, bytes);
            self.uploaded += bytes.len() as u64;
        }
        for (first, corners) in &update.corners {
            let bytes: &[u8] = bytemuck::cast_slice(corners);
            self.queue
                .write_buffer(&self.corners, *first as u64 * corner, bytes);
            self.uploaded += bytes.len() as u64;
        }
        self.corner_count = update.face_count * 3;
        self.dirty = true;
        Ok(())
    }

    /// The largest buffer one binding may hold on this device.
    fn binding_limit(&self) -> u64 {
        let limits = self.device.limits();
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
    }

    /// A buffer with room for `bytes` holding what `old` held, when `old` is too small.
    fn grown(&self, old: &wgpu::Buffer, label: &str, bytes: u64) -> Option<wgpu::Buffer> {
        if bytes <= old.size() {
            return None;
        }
        // Half as much again, so a growing mesh is not re-allocated every stroke.
        let size = (bytes * 3 / 2)
            .next_multiple_of(256)
            .min(self.binding_limit());
        let new = storage(&self.device, label, size);
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        encoder.copy_buffer_to_buffer(old, 0, &new, 0, old.size());
        self.queue.submit([encoder.finish()]);
        Some(new)
    }

    /// Bytes uploaded since the last call.
    pub fn take_uploaded(&mut self) -> u64 {
        std::mem::take(&mut self.uploaded)
    }

    /// Renders when dirty or resized; registers (or re-points) the egui texture.
    pub fn render(
        &mut self,
        renderer: &mut egui_wgpu::Renderer,
        size: (u32, u32),
        camera: &Camera,
        view: &ViewOptions,
    ) {
        let size = (size.0.max(1), size.1.max(1));
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
            let targets = PreviewTargets::new(&self.device, size, self.samples, sampled);
            match self.texture {
                Some(id) => renderer.update_egui_texture_from_wgpu_texture(
                    &self.device,
                    &targets.resolved_view,
                    wgpu::FilterMode::Linear,
                    id,
                ),
                None => {
                    self.texture = Some(renderer.register_native_texture(
                        &self.device,
                        &targets.resolved_view,
                        wgpu::FilterMode::Linear,
                    ))
                }
            }
            self.targets = Some(targets);
            self.dirty = true;
        }
        let options = RenderOptions {
            wireframe: view.wireframe,
            false_colour: view.false_colour,
            ..RenderOptions::default()
        };
        let mut uniforms = preview_uniforms(camera, &options);
        uniforms.hidden_layers = view.hidden_layers;
        uniforms.show_mask = view.show_mask as u32;
        if !self.dirty && self.drawn_with == Some(uniforms) {
            return;
        }
        self.dirty = false;
        self.drawn_with = Some(uniforms);
        self.queue
            .write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniforms));
        let targets = self.targets.as_ref().expect("made above");
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("viewport"),
            });
        let draws = [(self.bind_group.clone(), self.corner_count)];
        let draws = if self.corner_count > 0 {
            &draws[..]
        } else {
            &[]
        };
        record_preview_draws(&mut encoder, &self.pipeline, draws, targets);
        self.queue.submit([encoder.finish()]);
    }
}

fn storage(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

fn bind(
    device: &wgpu::Device,
    pipeline: &wgpu::RenderPipeline,
    uniform: &wgpu::Buffer,
    vertices: &wgpu::Buffer,
    corners: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let layout = pipeline.get_bind_group_layout(0);
    preview_bind_group(device, &layout, uniform, vertices, corners)
}
