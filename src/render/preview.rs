//! The preview renderer's host side: packs the mesh into draw chunks, renders offscreen with
//! `wgsl/render/preview.wgsl` and reads the image back. Works on any adapter with storage
//! buffers in the vertex stage, lavapipe included, so headless machines render too.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use thiserror::Error;

use super::brdf::Lighting;
use super::camera::{Camera, CameraSpec};
use super::image::Image;
use crate::gpu::shaders::{
    ENGINE_VERTEX_ENTRY, FRAGMENT_ENTRY, VERTEX_ENTRY, render_source, validate,
};
use crate::gpu::{GpuContext, GpuError};
use crate::mesh::{INVALID, LayerId, Mesh};

/// The colour target: 8-bit sRGB, so the shader writes linear radiance and the hardware
/// encodes it.
const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Samples per pixel when antialiasing (4 is what every WebGPU adapter supports).
pub(crate) const MSAA_SAMPLES: u32 = 4;
/// Above this many samples (pixels × samples) antialiasing is dropped: the multisampled colour
/// and depth targets would take more than 2 × 256 MiB.
const MAX_MSAA_SAMPLES_TOTAL: u64 = 64 << 20;
/// Largest image, in pixels (8192²): each of the resolve target, depth buffer and readback
/// buffer is then at most 256 MiB.
pub const MAX_PIXELS: u64 = 8192 * 8192;
/// Background, linear RGB: a mid-dark blue-grey that both white plaster and dark bark stand out
/// against.
pub const BACKGROUND: [f64; 3] = [0.10, 0.11, 0.13];
/// Edge width of the wireframe overlay, pixels.
const LINE_WIDTH: f32 = 1.0;

/// Per-layer false colours (linear RGB), repeating after eight layers.
pub const PALETTE: [[f32; 3]; 8] = [
    [0.80, 0.80, 0.78],
    [0.10, 0.35, 0.80],
    [0.85, 0.45, 0.05],
    [0.15, 0.60, 0.15],
    [0.70, 0.10, 0.55],
    [0.75, 0.70, 0.05],
    [0.05, 0.60, 0.65],
    [0.65, 0.12, 0.10],
];

/// One vertex as the shader reads it (`RenderVertex` in `wgsl/render/preview.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct RenderVertex {
    pub position: [f32; 3],
    pub layer: u32,
    pub normal: [f32; 3],
    pub roughness: f32,
    pub diffuse: [f32; 3],
    /// The sculpting mask (drawn only when [`PreviewUniforms::show_mask`] is 1).
    pub mask: f32,
    pub specular: [f32; 3],
    pub _pad1: f32,
}

/// The shader's uniforms (`PreviewUniforms` in `wgsl/render/preview.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct PreviewUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub key_direction: [f32; 4],
    pub key_irradiance: [f32; 4],
    pub fill_direction: [f32; 4],
    pub fill_irradiance: [f32; 4],
    pub sky: [f32; 4],
    pub ground: [f32; 4],
    pub wireframe: u32,
    pub false_colour: u32,
    pub line_width: f32,
    /// Bit `l`: layer `l` (< 32) is not drawn.
    pub hidden_layers: u32,
    pub show_mask: u32,
    pub _pad0: u32,
    pub _pad1: u32,
    pub _pad2: u32,
    pub palette: [[f32; 4]; 8],
}

#[derive(Debug, Error)]
pub enum RenderError {
    #[error("image size {width}×{height} is empty")]
    EmptySize { width: u32, height: u32 },
    #[error(
        "image size {width}×{height} is too large: this adapter renders at most {max}×{max} and {MAX_PIXELS} pixels in all"
    )]
    TooLarge { width: u32, height: u32, max: u32 },
    #[error("layer {layer} does not exist (the mesh has {layer_count} layers)")]
    NoSuchLayer { layer: LayerId, layer_count: usize },
    #[error("the adapter cannot read storage buffers in vertex shaders, which the preview needs")]
    NoVertexStorage,
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// What to render and how.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub camera: CameraSpec,
    /// Layers to draw; all when `None`. The camera frames what is drawn.
    pub layers: Option<Vec<LayerId>>,
    /// Every layer in its palette colour instead of its painted diffuse albedo.
    pub false_colour: bool,
    /// Dark edges over the shading.
    pub wireframe: bool,
    /// 4× multisampling (dropped automatically for very large images).
    pub antialias: bool,
    /// Most vertices one draw may use; the adapter's storage binding limit when `None`. Larger
    /// meshes are split into several draws.
    pub max_vertices_per_draw: Option<usize>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1280,
            height: 960,
            camera: CameraSpec::default(),
            layers: None,
            false_colour: false,
            wireframe: false,
            antialias: true,
            max_vertices_per_draw: None,
        }
    }
}

/// A rendered image and what went into it.
#[derive(Debug, Clone)]
pub struct Rendered {
    pub image: Image,
    /// Faces drawn (0 for an empty mesh or an empty layer choice: the image is background only).
    pub faces: usize,
    pub draws: usize,
    pub camera: Camera,
}

/// One draw: the vertices it uses, and three local vertex numbers per face.
#[derive(Default)]
struct Chunk {
    vertices: Vec<RenderVertex>,
    corners: Vec<u32>,
    /// Mesh vertex number of each of `vertices`.
    globals: Vec<u32>,
}

pub(crate) fn render_vertex(mesh: &Mesh, v: usize) -> RenderVertex {
    let brdf = mesh.brdfs()[v];
    let normal = mesh.normals()[v];
    RenderVertex {
        position: mesh.positions()[v].to_array(),
        layer: mesh.vertex_layers()[v],
        normal: if normal.is_finite() {
            normal.to_array()
        } else {
            [0.0; 3]
        },
        roughness: brdf.roughness,
        diffuse: brdf.diffuse,
        mask: mesh.flags()[v].mask(),
        specular: brdf.specular,
        _pad1: 0.0,
    }
}

/// Splits the live faces of the visible layers whose corners are all finite into chunks of at
/// most `max_vertices` vertices and `max_faces` faces, renumbering vertices per chunk. Also
/// returns the bounds of what is drawn.
fn build_chunks(
    mesh: &Mesh,
    visible: &[bool],
    max_vertices: usize,
    max_faces: usize,
) -> (Vec<Chunk>, Option<(Vec3, Vec3)>) {
    let positions = mesh.positions();
    // Local number of each mesh vertex in the chunk being filled.
    let mut local = vec![INVALID; mesh.vertex_count()];
    let mut chunks = Vec::new();
    let mut current = Chunk::default();
    let mut bounds: Option<(Vec3, Vec3)> = None;
    for (f, face) in mesh.faces().iter().enumerate() {
        if face[0] == INVALID
            || mesh.is_face_dead(f)
            || !visible[mesh.face_layers()[f] as usize]
            || face.iter().any(|&v| !positions[v as usize].is_finite())
        {
            continue;
        }
        let new_vertices = face
            .iter()
            .filter(|&&v| local[v as usize] == INVALID)
            .count();
        if current.vertices.len() + new_vertices > max_vertices
            || current.corners.len() / 3 >= max_faces
        {
            for &v in &current.globals {
                local[v as usize] = INVALID;
            }
            chunks.push(std::mem::take(&mut current));
        }
        for &v in face {
            let slot = &mut local[v as usize];
            if *slot == INVALID {
                *slot = current.vertices.len() as u32;
                current.vertices.push(render_vertex(mesh, v as usize));
                current.globals.push(v);
                let p = positions[v as usize];
                bounds = Some(match bounds {
                    None => (p, p),
                    Some((lo, hi)) => (lo.min(p), hi.max(p)),
                });
            }
            current.corners.push(*slot);
        }
    }
    if !current.corners.is_empty() {
        chunks.push(current);
    }
    (chunks, bounds)
}

/// Checks the size against the adapter and the pixel cap.
fn check_size(gpu: &GpuContext, width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 {
        return Err(RenderError::EmptySize { width, height });
    }
    let max = gpu.limits.max_texture_dimension_2d;
    if width > max || height > max || width as u64 * height as u64 > MAX_PIXELS {
        return Err(RenderError::TooLarge { width, height, max });
    }
    Ok(())
}

pub(crate) fn uniforms(camera: &Camera, options: &RenderOptions) -> PreviewUniforms {
    let lighting = Lighting::for_view(camera.right, camera.up, camera.toward);
    let four = |v: Vec3| v.extend(0.0).to_array();
    PreviewUniforms {
        view_proj: camera.view_proj.to_cols_array_2d(),
        eye: four(camera.eye),
        key_direction: four(lighting.key.direction),
        key_irradiance: four(lighting.key.irradiance),
        fill_direction: four(lighting.fill.direction),
        fill_irradiance: four(lighting.fill.irradiance),
        sky: four(lighting.sky),
        ground: four(lighting.ground),
        wireframe: options.wireframe as u32,
        false_colour: options.false_colour as u32,
        line_width: LINE_WIDTH,
        hidden_layers: 0,
        show_mask: 0,
        _pad0: 0,
        _pad1: 0,
        _pad2: 0,
        palette: PALETTE.map(|[r, g, b]| [r, g, b, 1.0]),
    }
}

/// Where the vertex stage reads each vertex's position and normal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum VertexPull {
    /// From the vertex rows, with everything else (`vs_main`).
    Rows,
    /// From the GPU backend's own position and normal buffers, the rest from the rows
    /// (`vs_engine`).
    Engine,
}

pub(crate) fn pipeline(
    device: &wgpu::Device,
    samples: u32,
    pull: VertexPull,
) -> Result<wgpu::RenderPipeline, GpuError> {
    let source = render_source("preview")?;
    // naga's messages carry source locations; wgpu's would not.
    validate("render/preview", &source)?;
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("preview"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("preview"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(match pull {
                VertexPull::Rows => VERTEX_ENTRY,
                VertexPull::Engine => ENGINE_VERTEX_ENTRY,
            }),
            compilation_options: Default::default(),
            buffers: &[],
        },
        // Layers are open sheets seen from both sides: no culling.
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: wgpu::MultisampleState {
            count: samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(FRAGMENT_ENTRY),
            compilation_options: Default::default(),
            targets: &[Some(COLOUR_FORMAT.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    if let Some(error) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Validation(error.to_string()));
    }
    Ok(pipeline)
}

fn target(
    device: &wgpu::Device,
    label: &str,
    (width, height): (u32, u32),
    samples: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// Renders `mesh` offscreen and reads the image back. An empty mesh, or a choice of layers with
/// nothing on them, gives an image of background only (`faces == 0`), never an error.
pub fn render(
    gpu: &GpuContext,
    mesh: &Mesh,
    options: &RenderOptions,
) -> Result<Rendered, RenderError> {
    let (width, height) = (options.width, options.height);
    check_size(gpu, width, height)?;
    let visible = visible_layers(mesh, options)?;
    if gpu.limits.max_storage_buffers_per_shader_stage < 2 {
        return Err(RenderError::NoVertexStorage);
    }
    let (max_vertices, max_faces) = chunk_limits(gpu, options);
    let (chunks, bounds) = build_chunks(mesh, &visible, max_vertices, max_faces);
    let faces: usize = chunks.iter().map(|c| c.corners.len() / 3).sum();
    let camera = Camera::fit(&options.camera, bounds, width as f32 / height as f32);

    let samples = if options.antialias
        && width as u64 * height as u64 * MSAA_SAMPLES as u64 <= MAX_MSAA_SAMPLES_TOTAL
    {
        MSAA_SAMPLES
    } else {
        1
    };
    let pipeline = pipeline(&gpu.device, samples, VertexPull::Rows)?;
    let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let uniform = gpu.uniform_buffer("preview uniforms", &uniforms(&camera, options));
    let draws = bind_chunks(gpu, &pipeline, &uniform, &chunks);
    drop(chunks);
    let copied = wgpu::TextureUsages::COPY_SRC;
    let targets = Targets::new(&gpu.device, (width, height), samples, copied);
    let readback = Readback::new(&gpu.device, width, height);
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("preview"),
        });
    record_draws(&mut encoder, &pipeline, &draws, &targets);
    readback.record_copy(&mut encoder, &targets.resolved);
    gpu.queue.submit([encoder.finish()]);
    if let Some(error) = pollster::block_on(scope.pop()) {
        return Err(GpuError::Validation(error.to_string()).into());
    }
    Ok(Rendered {
        image: Image {
            width,
            height,
            rgba: readback.read(gpu)?,
        },
        faces,
        draws: draws.len(),
        camera,
    })
}

/// Which layers the options show (all when none are named); a named layer the mesh lacks is
/// an error.
fn visible_layers(mesh: &Mesh, options: &RenderOptions) -> Result<Vec<bool>, RenderError> {
    let mut visible = vec![options.layers.is_none(); mesh.layer_count()];
    for &layer in options.layers.iter().flatten() {
        match visible.get_mut(layer as usize) {
            Some(slot) => *slot = true,
            None => {
                return Err(RenderError::NoSuchLayer {
                    layer,
                    layer_count: mesh.layer_count(),
                });
            }
        }
    }
    Ok(visible)
}

/// The most vertices and faces one draw may take: what fits the adapter's storage binding
/// and buffer limits (and the options' own cap on vertices).
fn chunk_limits(gpu: &GpuContext, options: &RenderOptions) -> (usize, usize) {
    let binding_limit = gpu
        .limits
        .max_storage_buffer_binding_size
        .min(gpu.limits.max_buffer_size);
    let fit_vertices = (binding_limit / std::mem::size_of::<RenderVertex>() as u64) as usize;
    let max_vertices = options
        .max_vertices_per_draw
        .unwrap_or(fit_vertices)
        .clamp(3, fit_vertices.max(3));
    (max_vertices, (binding_limit / 12) as usize)
}

/// The shader's bindings: the uniforms, the vertex rows and the corners (three vertex numbers
/// per face), and for [`VertexPull::Engine`] the GPU backend's positions and normals.
pub(crate) fn bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    uniform: &wgpu::Buffer,
    (vertices, corners): (&wgpu::Buffer, &wgpu::Buffer),
    engine: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
) -> wgpu::BindGroup {
    let engine = engine.map(|(positions, normals)| [positions, normals]);
    let entries: Vec<wgpu::BindGroupEntry> = [uniform, vertices, corners]
        .into_iter()
        .chain(engine.into_iter().flatten())
        .enumerate()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("preview"),
        layout,
        entries: &entries,
    })
}

/// One bind group per chunk (the uniforms, its vertices and corners), with its corner count.
fn bind_chunks(
    gpu: &GpuContext,
    pipeline: &wgpu::RenderPipeline,
    uniform: &wgpu::Buffer,
    chunks: &[Chunk],
) -> Vec<(wgpu::BindGroup, u32)> {
    let layout = pipeline.get_bind_group_layout(0);
    chunks
        .iter()
        .map(|chunk| {
            let vertices = gpu.storage_buffer("preview vertices", &chunk.vertices, false);
            let corners = gpu.storage_buffer("preview corners", &chunk.corners, false);
            let group = bind_group(&gpu.device, &layout, uniform, (&vertices, &corners), None);
            (group, chunk.corners.len() as u32)
        })
        .collect()
}

/// The render targets: the image (resolved, copied out), its multisampled twin when
/// antialiasing, and depth; each texture kept beside its view for the pass.
pub(crate) struct Targets {
    pub(crate) size: (u32, u32),
    resolved: wgpu::Texture,
    /// What the pass leaves its image in (the resolve target when multisampled).
    pub(crate) resolved_view: wgpu::TextureView,
    multisampled: Option<(wgpu::Texture, wgpu::TextureView)>,
    depth: (wgpu::Texture, wgpu::TextureView),
}

impl Targets {
    /// The image's RGBA bytes, copied out on `device` (the app's viewport, in its tests; the
    /// image must have been made with `COPY_SRC`).
    #[cfg(test)]
    pub(crate) fn read_image(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u8>, GpuError> {
        let readback = Readback::new(device, self.size.0, self.size.1);
        let mut encoder = device.create_command_encoder(&Default::default());
        readback.record_copy(&mut encoder, &self.resolved);
        queue.submit([encoder.finish()]);
        let padded = crate::gpu::map_read(device, &readback.buffer)?;
        Ok(readback.unpadded(&padded))
    }

    /// Colour and depth targets of `size` at `samples` per pixel; the image also gets
    /// `image_usage` (copied out by `render`, sampled by the app's viewport).
    pub(crate) fn new(
        device: &wgpu::Device,
        size: (u32, u32),
        samples: u32,
        image_usage: wgpu::TextureUsages,
    ) -> Targets {
        let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let with_view = |texture: wgpu::Texture| {
            let view = texture.create_view(&Default::default());
            (texture, view)
        };
        let image = attachment | image_usage;
        let resolved = target(device, "preview image", size, 1, COLOUR_FORMAT, image);
        let multisampled = (samples > 1).then(|| {
            let name = "preview samples";
            with_view(target(
                device,
                name,
                size,
                samples,
                COLOUR_FORMAT,
                attachment,
            ))
        });
        let depth = target(
            device,
            "preview depth",
            size,
            samples,
            DEPTH_FORMAT,
            attachment,
        );
        Targets {
            size,
            resolved_view: resolved.create_view(&Default::default()),
            resolved,
            multisampled,
            depth: with_view(depth),
        }
    }
}

/// Records the render pass: cleared to the background, every chunk drawn, resolved into the
/// image when multisampled.
pub(crate) fn record_draws(
    encoder: &mut wgpu::CommandEncoder,
    pipeline: &wgpu::RenderPipeline,
    draws: &[(wgpu::BindGroup, u32)],
    targets: &Targets,
) {
    let [r, g, b] = BACKGROUND;
    let (view, resolve_target) = match &targets.multisampled {
        Some((_, samples_view)) => (samples_view, Some(&targets.resolved_view)),
        None => (&targets.resolved_view, None),
    };
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("preview"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &targets.depth.1,
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
    pass.set_pipeline(pipeline);
    for (group, corners) in draws {
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..*corners, 0..1);
    }
}

/// The buffer the image is copied into, its rows padded to the copy alignment.
struct Readback {
    buffer: wgpu::Buffer,
    width: u32,
    height: u32,
    padded_row_bytes: u32,
}

impl Readback {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Readback {
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row_bytes = (4 * width).div_ceil(align) * align;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("preview readback"),
            size: padded_row_bytes as u64 * height as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Readback {
            buffer,
            width,
            height,
            padded_row_bytes,
        }
    }

    fn record_copy(&self, encoder: &mut wgpu::CommandEncoder, image: &wgpu::Texture) {
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: image,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row_bytes),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
    }

    /// The image's RGBA bytes, the padding dropped.
    fn read(&self, gpu: &GpuContext) -> Result<Vec<u8>, GpuError> {
        Ok(self.unpadded(&gpu.map_read(&self.buffer)?))
    }

    fn unpadded(&self, padded: &[u8]) -> Vec<u8> {
        let row_bytes = 4 * self.width as usize;
        let mut rgba = Vec::with_capacity(row_bytes * self.height as usize);
        for row in padded.chunks_exact(self.padded_row_bytes as usize) {
            rgba.extend_from_slice(&row[..row_bytes]);
        }
        rgba
    }
}
