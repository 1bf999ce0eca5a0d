//! The viewport's GPU side: the mesh's render rows in one storage buffer (indexed by vertex
//! number, so a stroke's changed vertices are written in place), the live faces' corners in
//! another, drawn with the preview renderer's shader (`wgsl/render/preview.wgsl`) into a
//! texture the app owns and egui shows. It renders only when the camera, the options or the
//! mesh changed.
//!
//! On the GPU backend's own device the vertex stage reads positions and normals from the
//! backend's buffers ([`EngineVertices`], `vs_engine`), which the engine keeps current as it
//! sculpts, and the rows carry only layer, material and mask. The viewport then draws what
//! the engine has submitted by the time it draws: mid-batch, a step whose exact check is still
//! to come can show for a frame before the next update, and at a stroke's end its remesh (new
//! positions under the old faces) until the update with the new faces arrives.

use eframe::{egui, egui_wgpu};

use super::upload::MeshUpdate;
use crate::gpu::GpuError;
use crate::pipeline::EngineVertices;
use crate::render::{
    Camera, MSAA_SAMPLES, PreviewTargets, PreviewUniforms, RenderOptions, RenderVertex, VertexPull,
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
    /// Where positions and normals come from the GPU backend's buffers: those, and the
    /// pipeline that reads them (`vs_engine`), made when first needed.
    engine: Option<EngineVertices>,
    engine_pipeline: Option<wgpu::RenderPipeline>,
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
        let pipeline = preview_pipeline(device, samples, VertexPull::Rows)?;
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewport uniforms"),
            size: std::mem::size_of::<PreviewUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let vertices = storage(device, "viewport vertices", 64);
        let corners = storage(device, "viewport corners", 64);
        let bind_group = bind(device, &pipeline, &uniform, (&vertices, &corners), None);
        Ok(Viewport {
            device: device.clone(),
            queue: queue.clone(),
            pipeline,
            engine: None,
            engine_pipeline: None,
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
            self.draw_nothing();
            return Err(format!(
                "the viewport cannot draw {} vertices: {} MiB of vertex rows, over this adapter's storage binding limit of {} MiB",
                update.vertex_count,
                vertex_bytes.max(corner_bytes) >> 20,
                limit >> 20
            ));
        }
        // What can fail comes before anything changes.
        if let Some(engine) = &update.engine
            && engine.count != update.vertex_count as usize
        {
            self.draw_nothing();
            return Err(format!(
                "the engine's vertex buffers hold {} vertices, the mesh {}",
                engine.count, update.vertex_count
            ));
        }
        if update.engine.is_some() && self.engine_pipeline.is_none() {
            let pipeline = preview_pipeline(&self.device, self.samples, VertexPull::Engine);
            match pipeline {
                Ok(pipeline) => self.engine_pipeline = Some(pipeline),
                Err(e) => {
                    self.draw_nothing();
                    return Err(format!("the viewport cannot draw from the engine: {e}"));
                }
            }
        }
        let grown_vertices = self.grown(&self.vertices, "viewport vertices", vertex_bytes);
        let grown_corners = self.grown(&self.corners, "viewport corners", corner_bytes);
        let rebind =
            grown_vertices.is_some() || grown_corners.is_some() || self.engine != update.engine;
        if let Some(grown) = grown_vertices {
            self.vertices = grown;
        }
        if let Some(grown) = grown_corners {
            self.corners = grown;
        }
        self.engine = update.engine.clone();
        if rebind {
            let engine = (self.engine.as_ref()).map(|e| (&e.positions, &e.normals));
            let buffers = (&self.vertices, &self.corners);
            self.bind_group = bind(
                &self.device,
                self.pipeline(),
                &self.uniform,
                buffers,
                engine,
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

    /// After an update that could not be applied: nothing is drawn (rather than rows that no
    /// longer match what the engine sent).
    fn draw_nothing(&mut self) {
        self.corner_count = 0;
        self.dirty = true;
    }

    /// The pipeline for where positions and normals come from now.
    fn pipeline(&self) -> &wgpu::RenderPipeline {
        match (&self.engine, &self.engine_pipeline) {
            (Some(_), Some(engine)) => engine,
            _ => &self.pipeline,
        }
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

    /// Whether positions and normals come from the GPU backend's own buffers.
    pub fn draws_from_engine(&self) -> bool {
        self.engine.is_some()
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
        if self.fit_targets(size) {
            let image = &self.targets.as_ref().expect("fitted").resolved_view;
            let filter = wgpu::FilterMode::Linear;
            match self.texture {
                Some(id) => {
                    renderer.update_egui_texture_from_wgpu_texture(&self.device, image, filter, id)
                }
                None => {
                    let id = renderer.register_native_texture(&self.device, image, filter);
                    self.texture = Some(id);
                }
            }
        }
        self.draw(camera, view);
    }

    /// Makes the targets when there are none of `size` yet (then `true`).
    fn fit_targets(&mut self, size: (u32, u32)) -> bool {
        let size = (size.0.max(1), size.1.max(1));
        if self.targets.as_ref().is_some_and(|t| t.size == size) {
            return false;
        }
        // Sampled by egui; copied out by the tests.
        let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
        self.dirty = true;
        self.targets = Some(PreviewTargets::new(&self.device, size, self.samples, usage));
        true
    }

    /// Draws into the targets when dirty or the camera or view changed.
    fn draw(&mut self, camera: &Camera, view: &ViewOptions) {
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
        let targets = self.targets.as_ref().expect("made by fit_targets");
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
        record_preview_draws(&mut encoder, self.pipeline(), draws, targets);
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
    rows: (&wgpu::Buffer, &wgpu::Buffer),
    engine: Option<(&wgpu::Buffer, &wgpu::Buffer)>,
) -> wgpu::BindGroup {
    let layout = pipeline.get_bind_group_layout(0);
    preview_bind_group(device, &layout, uniform, rows, engine)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::app::SharedDevice;
    use crate::app::upload::Mirror;
    use crate::bench::{ScriptSpec, generate_script};
    use crate::brush::Stroke;
    use crate::gpu::{AdapterChoice, GpuContext, GpuKernels};
    use crate::mesh::Mesh;
    use crate::pipeline::{Pipeline, PipelineSettings};
    use crate::render::CameraSpec;
    use crate::scene::{SceneKind, SceneSpec, generate};

    fn gpu() -> GpuContext {
        GpuContext::new(AdapterChoice {
            allow_software: true,
        })
        .expect("GPU tests need an adapter (run tools/test.sh)")
    }

    /// A viewport on `device`, fed by its own mirror: from the rows, or from the engine's
    /// buffers.
    struct Fed {
        viewport: Viewport,
        mirror: Mirror,
        engine: bool,
    }

    impl Fed {
        fn new(device: &SharedDevice, engine: bool) -> Fed {
            let viewport = Viewport::new(&device.device, &device.queue, false).unwrap();
            let mirror = Mirror::default();
            Fed {
                viewport,
                mirror,
                engine,
            }
        }

        /// Sends what changed; returns the update.
        fn update(
            &mut self,
            mesh: &Mesh,
            changed: Option<&[u32]>,
            buffers: Option<EngineVertices>,
        ) -> MeshUpdate {
            let buffers = buffers.filter(|_| self.engine);
            let from_engine = buffers.is_some();
            let update = self
                .mirror
                .update(mesh, changed, changed.is_none(), buffers);
            self.viewport.apply(&update).unwrap();
            assert_eq!(self.viewport.draws_from_engine(), from_engine);
            update
        }

        fn picture(&mut self, device: &SharedDevice, mesh: &Mesh) -> Vec<u8> {
            let camera = Camera::fit(&CameraSpec::default(), mesh.bounds(), 4.0 / 3.0);
            self.viewport.fit_targets((320, 240));
            self.viewport.draw(&camera, &ViewOptions::default());
            let targets = self.viewport.targets.as_ref().expect("fitted");
            targets.read_image(&device.device, &device.queue).unwrap()
        }
    }

    fn same_pictures(device: &SharedDevice, mesh: &Mesh, fed: [&mut Fed; 2]) {
        let [a, b] = fed.map(|f| f.picture(device, mesh));
        let background = a.chunks(4).filter(|p| p[..3] == a[..3]).count();
        assert!(
            background < a.len() / 4 * 9 / 10,
            "the mesh is in the picture"
        );
        assert!(a == b, "the two pictures differ");
    }

    /// A 2K-face plaster, and a stroke of the bench's script that only moves vertices until
    /// it ends (a grab also remeshes between samples).
    fn plaster_and_plain_stroke() -> (Mesh, Stroke) {
        let mesh = generate(&SceneSpec {
            kind: SceneKind::Plaster,
            triangles: 2000,
            seed: 3,
        })
        .unwrap();
        let spec = ScriptSpec {
            strokes: 8,
            samples: 12,
            ..ScriptSpec::default()
        };
        let strokes = generate_script(&mesh, &spec)
            .resolve(&mesh, "test")
            .unwrap();
        let plain = (strokes.into_iter())
            .find(|s| !s.settings().brush.kind.drags())
            .unwrap();
        (mesh, plain)
    }

    /// On the GPU backend's device (lavapipe here) the viewport draws positions and normals
    /// from the backend's own buffers: a sculpting stroke sends it no rows, only a redraw, and
    /// the picture is the one rows uploaded from the mesh give, pixel for pixel.
    #[test]
    fn the_engines_buffers_draw_the_rows_picture_and_a_stroke_uploads_no_rows() {
        let (mut mesh, plain) = plaster_and_plain_stroke();
        let context = gpu();
        let shared = SharedDevice::of(&context);
        let kernels = Box::new(GpuKernels::new(context));
        let mut pipeline = Pipeline::with_kernels(PipelineSettings::default(), kernels);
        let (mut rows, mut engine) = (Fed::new(&shared, false), Fed::new(&shared, true));
        let buffers = pipeline.vertex_buffers(&mesh);
        assert!(rows.update(&mesh, None, None).bytes() > 0);
        assert!(
            engine.update(&mesh, None, buffers).bytes() > 0,
            "layers and materials"
        );
        same_pictures(&shared, &mesh, [&mut rows, &mut engine]);

        let mut stroke = (pipeline.begin_stroke(&mut mesh, plain.settings())).unwrap();
        let report = stroke.add_samples(&plain.samples).unwrap();
        assert!(!report.changed.is_empty() && !report.topology_changed);
        let buffers = stroke.vertex_buffers();
        let changed = Some(&report.changed[..]);
        let sculpted = engine.update(stroke.mesh(), changed, buffers);
        assert_eq!(
            sculpted.bytes(),
            0,
            "positions and normals are the engine's"
        );
        assert!(sculpted.redraw && !sculpted.is_empty());
        let uploaded = rows.update(stroke.mesh(), changed, None);
        assert!(uploaded.bytes() > 0 && !uploaded.redraw);
        same_pictures(&shared, stroke.mesh(), [&mut rows, &mut engine]);
        let remesh = stroke.finish().unwrap().remesh;
        assert!(remesh.splits + remesh.collapses > 0, "{remesh:?}");

        // Remeshed: the whole mesh compared, as the app does after a stroke.
        let buffers = pipeline.vertex_buffers(&mesh);
        engine.update(&mesh, None, buffers);
        rows.update(&mesh, None, None);
        same_pictures(&shared, &mesh, [&mut rows, &mut engine]);

        // The backend's copy uploaded afresh (as after an open): new buffers, bound again.
        pipeline.forget_mesh();
        let buffers = pipeline.vertex_buffers(&mesh);
        let rebound = engine.update(&mesh, None, buffers);
        assert!(rebound.redraw && rebound.bytes() == 0);
        same_pictures(&shared, &mesh, [&mut rows, &mut engine]);
    }

    /// A GPU that gives up (a lost device) sends the viewport back to rows: every row again,
    /// and the rows' picture.
    #[test]
    fn a_gpu_that_gives_up_sends_the_viewport_back_to_rows() {
        let (mut mesh, plain) = plaster_and_plain_stroke();
        let context = gpu();
        let shared = SharedDevice::of(&context);
        let mut kernels = GpuKernels::new(context);
        kernels.fail_after(0);
        let mut pipeline = Pipeline::with_kernels(PipelineSettings::default(), Box::new(kernels));
        let (mut rows, mut engine) = (Fed::new(&shared, false), Fed::new(&shared, true));
        rows.update(&mesh, None, None);
        let buffers = pipeline.vertex_buffers(&mesh);
        assert!(
            buffers.is_some(),
            "a copy is uploaded before the first stroke"
        );
        engine.update(&mesh, None, buffers);

        pipeline.apply_stroke(&mut mesh, &plain).unwrap();
        assert!(
            pipeline.kernel_failure().is_some(),
            "the stroke ran on the CPU"
        );
        let buffers = pipeline.vertex_buffers(&mesh);
        assert!(buffers.is_none());
        let back = engine.update(&mesh, None, buffers);
        let row = std::mem::size_of::<RenderVertex>();
        assert!(back.bytes() >= mesh.vertex_count() * row && back.engine.is_none());
        rows.update(&mesh, None, None);
        same_pictures(&shared, &mesh, [&mut rows, &mut engine]);
    }
}
