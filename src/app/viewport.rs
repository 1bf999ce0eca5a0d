//! The viewport's GPU side: the mesh's render rows in one storage buffer (indexed by vertex
//! number, so a stroke's changed vertices are written in place), the live faces' corners in
//! another, drawn with the preview renderer's shader (`wgsl/render/preview.wgsl`) into a
//! texture the app owns and egui shows. It renders only when the camera, the options or the
//! mesh changed.

use eframe::{egui, egui_wgpu};

use super::upload::MeshUpdate;
use crate::gpu::GpuError;
use crate::render::{
    COLOUR_FORMAT, Camera, DEPTH_FORMAT, MSAA_SAMPLES, PreviewUniforms, RenderOptions,
    RenderVertex, preview_bind_group, preview_pipeline, preview_uniforms,
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
    targets: Option<Targets>,
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

struct Targets {
    size: (u32, u32),
    resolved: wgpu::TextureView,
    /// `None` without antialiasing: the pass draws straight into `resolved`.
    multisampled: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
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
        let vertices_grown = self.grow(Grown::Vertices, vertex_bytes);
        let corners_grown = self.grow(Grown::Corners, corner_bytes);
        if vertices_grown || corners_grown {
            self.bind_group = bind(
                &self.device,
                &self.pipeline,
                &self.uniform,
                &self.vertices,
                &self.corners,
            );
        }
        for (first, rows) in &update.rows {
            self.write(
                &self.vertices.clone(),
                *first as u64 * row,
                bytemuck::cast_slice(rows),
            );
        }
        for (first, corners) in &update.corners {
            let bytes: &[u8] = bytemuck::cast_slice(corners);
            self.write(&self.corners.clone(), *first as u64 * corner, bytes);
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

    /// Replaces a buffer by one with room for `bytes`, copying what it held; whether it did.
    fn grow(&mut self, which: Grown, bytes: u64) -> bool {
        let old = match which {
            Grown::Vertices => &self.vertices,
            Grown::Corners => &self.corners,
        };
        if bytes <= old.size() {
            return false;
        }
        let label = match which {
            Grown::Vertices => "viewport vertices",
            Grown::Corners => "viewport corners",
        };
        let new = storage(&self.device, label, grown(bytes).min(self.binding_limit()));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        encoder.copy_buffer_to_buffer(old, 0, &new, 0, old.size());
        self.queue.submit([encoder.finish()]);
        match which {
            Grown::Vertices => self.vertices = new,
            Grown::Corners => self.corners = new,
        }
        true
    }

    fn write(&mut self, buffer: &wgpu::Buffer, offset: u64, bytes: &[u8]) {
        // Buffer writes must be whole multiples of 4 bytes; every row and corner is.
        if !bytes.is_empty() {
            self.queue.write_buffer(buffer, offset, bytes);
            self.uploaded += bytes.len() as u64;
        }
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
            let targets = Targets::new(&self.device, size, self.samples);
            match self.texture {
                Some(id) => renderer.update_egui_texture_from_wgpu_texture(
                    &self.device,
                    &targets.resolved,
                    wgpu::FilterMode::Linear,
                    id,
                ),
                None => {
                    self.texture = Some(renderer.register_native_texture(
                        &self.device,
                        &targets.resolved,
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
        {
            let background = crate::render::BACKGROUND;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewport"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: targets.multisampled.as_ref().unwrap_or(&targets.resolved),
                    depth_slice: None,
                    resolve_target: targets.multisampled.as_ref().map(|_| &targets.resolved),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: background[0],
                            g: background[1],
                            b: background[2],
                            a: 1.0,
                        }),
                        // Multisampled, only the resolved image is kept.
                        store: if targets.multisampled.is_some() {
                            wgpu::StoreOp::Discard
                        } else {
                            wgpu::StoreOp::Store
                        },
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if self.corner_count > 0 {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.draw(0..self.corner_count, 0..1);
            }
        }
        self.queue.submit([encoder.finish()]);
    }
}

impl Targets {
    fn new(device: &wgpu::Device, size: (u32, u32), samples: u32) -> Targets {
        let texture = |label, samples, format, usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size.0,
                        height: size.1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        Targets {
            size,
            resolved: texture(
                "viewport image",
                1,
                COLOUR_FORMAT,
                attachment | wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            multisampled: (samples > 1)
                .then(|| texture("viewport samples", samples, COLOUR_FORMAT, attachment)),
            depth: texture("viewport depth", samples, DEPTH_FORMAT, attachment),
        }
    }
}

#[derive(Clone, Copy)]
enum Grown {
    Vertices,
    Corners,
}

/// Room for `bytes` and half as much again, so a growing mesh is not re-allocated every stroke.
fn grown(bytes: u64) -> u64 {
    (bytes * 3 / 2).next_multiple_of(256)
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
