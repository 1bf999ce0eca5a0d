//! `slayer gui`: the interactive sculpting app (eframe, on its wgpu backend).
//!
//! The UI thread draws and reads input; the engine runs on a worker thread ([`worker`]) that
//! owns the session and the pipeline. Each pointer event of a stroke becomes a ray sent to the
//! worker, which picks it onto the surface, runs the samples through the streaming stroke API
//! and answers with the rows of the vertices that changed; the UI writes those rows into its
//! GPU buffers ([`viewport`]) and redraws. Nothing on the UI thread waits for the engine.
//!
//! ```text
//!   UI thread:  input ─► Command ──────────────► worker: Session + Pipeline + Picker
//!               viewport ◄─ MeshUpdate, Status ◄─┘
//! ```

mod camera;
mod input;
mod panels;
mod pick;
mod replay;
mod upload;
mod viewport;
mod worker;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, Sender};
use std::thread::JoinHandle;
use std::time::Instant;

pub use camera::OrbitCamera;
pub use pick::{Hit, Picker, Ray};
pub use replay::{ExitPlan, Metrics};
pub use upload::{MeshUpdate, Mirror};
pub use viewport::ViewOptions;
pub use worker::{Command, NewLayer, Reply, Status, StrokePoint};

use eframe::{egui, egui_wgpu};

use crate::brush::{BrushKind, Stroke};
use crate::mesh::Brdf;
use crate::pipeline::{PhaseTimes, Pipeline};
use crate::session::{BrushSettings, LayerSettings, Session};
use crate::topology::ProximityPolicy;
use input::PointerState;
use viewport::Viewport;

/// The engine's GPU device, for the window to draw with: one device for both, so the
/// viewport's buffers live beside the backend's.
#[derive(Clone)]
pub struct SharedDevice {
    /// A software rasterizer (lavapipe): one queue for the engine and the window.
    pub software: bool,
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl SharedDevice {
    pub fn of(gpu: &crate::gpu::GpuContext) -> SharedDevice {
        SharedDevice {
            software: gpu.adapter.software,
            instance: gpu.instance.clone(),
            adapter: gpu.wgpu_adapter.clone(),
            device: gpu.device.clone(),
            queue: gpu.queue.clone(),
        }
    }
}

/// Everything the app starts from.
pub struct AppSetup {
    pub session: Session,
    pub pipeline: Pipeline,
    /// Where Ctrl-S writes the session.
    pub save_path: PathBuf,
    /// Strokes to play through the pointer's path before handing over to the user.
    pub replay: Vec<Stroke>,
    pub plan: ExitPlan,
    /// Draw the viewport with 4× multisampling.
    pub antialias: bool,
}

/// The brush and what it paints, as the panels set them.
#[derive(Debug, Clone, PartialEq)]
pub struct Tools {
    pub brush: BrushSettings,
    /// Paint the material below while any brush deforms (the paint brush always paints).
    pub paint_while_sculpting: bool,
    pub material: Brdf,
    pub material_name: String,
    pub opacity: f32,
    /// Lay the material down through a generated pattern of it and a second preset.
    pub stencil: Option<StencilChoice>,
    /// Mirror strokes across the plane x = the scene's centre.
    pub symmetry_x: bool,
    pub remesh: bool,
    /// A drag on the mesh traces this layer tool instead of stroking the brush.
    pub trace: Option<Trace>,
    /// How far a patch or a duplicate is lifted off its surface, in edge lengths (the
    /// collision distance is one).
    pub lift_edges: f32,
    /// A patch or a duplicate this many edge lengths thick, a closed shell; 0: an open sheet.
    pub thickness_edges: f32,
    pub view: ViewOptions,
    /// The engine's phase times in the status bar (off for pictures that must not change
    /// from run to run).
    pub phase_times: bool,
}

/// The layer tools a drag traces (`docs/layers.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Trace {
    /// Cut the active layers open along the drag.
    Cut,
    /// A new layer in the brush's material filling the closed drag.
    Patch,
}

/// A generated stencil: `pattern` of the brush's material and `second`, repeating every
/// `tile` world units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StencilChoice {
    pub pattern: crate::brush::Pattern,
    pub second: &'static str,
    pub tile: f32,
}

/// Stroke samples sent and done since the app started (running totals: a reply that comes
/// after the next stroke began still counts where it belongs), and the engine's last phase
/// times.
#[derive(Debug, Clone, Default)]
pub struct Progress {
    pub sent: usize,
    pub done: usize,
    pub phases: PhaseTimes,
}

pub struct SlayerApp {
    commands: Sender<Command>,
    replies: Receiver<Reply>,
    worker: Option<JoinHandle<()>>,
    viewport: Result<Viewport, String>,
    renderer: Option<Arc<egui::mutex::RwLock<egui_wgpu::Renderer>>>,
    camera: Option<OrbitCamera>,
    /// The document as the worker last reported it.
    pub status: Status,
    pub tools: Tools,
    pointer: PointerState,
    hover: Option<Hit>,
    pub progress: Progress,
    /// What the last finished stroke did.
    pub last_stroke: Option<crate::pipeline::StrokeReport>,
    /// Errors and notices, newest last, with when they came.
    messages: Vec<(String, Instant)>,
    help: bool,
    save_path: PathBuf,
    replay: Option<replay::Replay>,
    pub metrics: Metrics,
    metrics_path: Option<PathBuf>,
    open_path: Option<String>,
    rename: Option<(u32, String)>,
    /// Where the viewport was drawn last frame, in points.
    viewport_rect: Option<egui::Rect>,
    /// The window may close without asking (the user chose, or the replay closes it).
    close_confirmed: bool,
    /// The unsaved-changes question is shown; `Some(true)`: quit once the save is done.
    closing: Option<bool>,
    /// The engine thread's end, when it ended early.
    engine_stopped: Option<String>,
    /// A status came from the engine (the panels can be laid out).
    status_received: bool,
    /// The mesh's box as of the last whole upload (`Some(None)`: an empty mesh).
    scene_bounds: Option<Option<(glam::Vec3, glam::Vec3)>>,
    started: Instant,
}

impl SlayerApp {
    /// The app on eframe's wgpu device; the engine thread starts here.
    pub fn new(cc: &eframe::CreationContext<'_>, setup: AppSetup) -> SlayerApp {
        SlayerApp::on_device(cc, setup, false)
    }

    /// [`SlayerApp::new`]; `shares_engine_device`: eframe's device is the GPU backend's (only
    /// [`run`] knows), so the viewport reads positions and normals from the backend's buffers.
    fn on_device(
        cc: &eframe::CreationContext<'_>,
        setup: AppSetup,
        shares_engine_device: bool,
    ) -> SlayerApp {
        let (commands, worker_commands) = mpsc::channel();
        let (worker_replies, replies) = mpsc::channel();
        let ctx = cc.egui_ctx.clone();
        let wake = Box::new(move || ctx.request_repaint());
        let edge = setup.session.mesh().mean_edge_length();
        let brush = setup.session.brush;
        let worker = worker::Worker::new(
            setup.session,
            setup.pipeline,
            worker_commands,
            worker_replies,
            wake,
            shares_engine_device,
        );
        let handle = std::thread::Builder::new()
            .name("slayer engine".into())
            .spawn(move || worker.run())
            .expect("the engine thread starts");
        let (viewport, renderer) = match &cc.wgpu_render_state {
            Some(state) => (
                Viewport::new(&state.device, &state.queue, setup.antialias)
                    .map_err(|e| e.to_string()),
                Some(state.renderer.clone()),
            ),
            None => (Err("eframe runs without wgpu: no viewport".into()), None),
        };
        let preset = crate::material::PAINT;
        SlayerApp {
            commands,
            replies,
            worker: Some(handle),
            viewport,
            renderer,
            camera: None,
            status: Status::default(),
            tools: Tools {
                brush: BrushSettings {
                    radius: brush.radius.max(edge),
                    ..brush
                },
                paint_while_sculpting: false,
                material: preset.brdf,
                material_name: preset.name.into(),
                opacity: 1.0,
                stencil: None,
                symmetry_x: false,
                remesh: true,
                trace: None,
                lift_edges: 2.0,
                thickness_edges: 0.0,
                view: ViewOptions {
                    show_mask: true,
                    ..ViewOptions::default()
                },
                phase_times: true,
            },
            pointer: PointerState::default(),
            hover: None,
            progress: Progress::default(),
            last_stroke: None,
            messages: Vec::new(),
            help: false,
            save_path: setup.save_path,
            metrics_path: setup.plan.metrics.clone(),
            replay: Some(replay::Replay::new(setup.replay, setup.plan)).filter(|r| !r.is_empty()),
            metrics: Metrics::default(),
            open_path: None,
            rename: None,
            viewport_rect: None,
            close_confirmed: false,
            closing: None,
            scene_bounds: None,
            engine_stopped: None,
            status_received: false,
            started: Instant::now(),
        }
    }

    pub(crate) fn send(&self, command: Command) {
        // The worker only stops when the app does.
        let _ = self.commands.send(command);
    }

    /// What `question` says of the session once every command sent so far is done. Blocks
    /// until then: for tests, never in a frame of the user's.
    pub fn query<T: Send + 'static>(
        &self,
        question: impl FnOnce(&Session) -> T + Send + 'static,
    ) -> Option<T> {
        let (answer, wait) = mpsc::channel();
        self.send(Command::Query(Box::new(move |session| {
            // The asker may have given up waiting: nothing to do then.
            let _ = answer.send(question(session));
        })));
        wait.recv().ok()
    }

    /// Shows or hides a layer (the Layers panel's eye), as one history entry.
    pub fn set_layer_visible(&self, layer: u32, visible: bool) {
        if let Some((_, settings)) = self.status.layers.get(layer as usize) {
            self.send(Command::SetLayer(
                layer,
                LayerSettings {
                    visible,
                    ..*settings
                },
            ));
        }
    }

    /// Where the pointer last met the surface.
    pub fn hover(&self) -> Option<Hit> {
        self.hover
    }

    /// No stroke in progress and every sent sample done (or the engine gone: nothing more
    /// will be).
    pub fn idle(&self) -> bool {
        self.engine_stopped.is_some()
            || (!self.pointer.stroking() && self.progress.done >= self.progress.sent)
    }

    /// The replay (if any) and what follows it are done.
    pub fn replay_finished(&self) -> bool {
        self.replay.as_ref().is_none_or(|r| r.finished())
    }

    /// The unsaved-changes question is on screen (a close was held back).
    pub fn asking_to_save(&self) -> bool {
        self.closing == Some(false)
    }

    /// The window may close now without asking.
    pub fn may_close(&self) -> bool {
        self.close_confirmed || !self.status.unsaved
    }

    /// Where the viewport was drawn last frame, in points.
    pub fn viewport_rect(&self) -> Option<egui::Rect> {
        self.viewport_rect
    }

    /// The viewport's width over its height (the window's shape before the first frame).
    pub(crate) fn aspect(&self) -> f32 {
        self.viewport_rect
            .map_or(1.5, |r| r.width() / r.height().max(1.0))
    }

    pub fn camera(&self) -> Option<&OrbitCamera> {
        self.camera.as_ref()
    }

    /// A close with unsaved changes is held until the user says save, discard or cancel.
    fn ask_before_closing(&mut self, ctx: &egui::Context) {
        let requested = ctx.input(|i| i.viewport().close_requested());
        if requested
            && self.status.unsaved
            && !self.close_confirmed
            && self.engine_stopped.is_none()
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.closing.get_or_insert(false);
        }
        if self.closing != Some(false) {
            return;
        }
        let mut choice = None;
        egui::Modal::new(egui::Id::unique("unsaved")).show(ctx, |ui| {
            ui.heading("Unsaved changes");
            ui.label(format!(
                "Save the session to {} before quitting?",
                self.save_path.display()
            ));
            ui.horizontal(|ui| {
                if ui.button("Save and quit").clicked() {
                    choice = Some("save");
                }
                if ui.button("Quit without saving").clicked() {
                    choice = Some("discard");
                }
                if ui.button("Cancel").clicked() {
                    choice = Some("cancel");
                }
            });
        });
        match choice {
            Some("save") => {
                self.closing = Some(true);
                self.send(Command::Save(self.save_path.clone()));
            }
            Some("discard") => {
                self.close_confirmed = true;
                self.closing = None;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Some(_) => self.closing = None,
            None => {}
        }
    }

    /// The engine thread ended (a panic): say why, once; the window stays for saving nothing
    /// more, but does not spin.
    fn engine_gone(&mut self) {
        if self.engine_stopped.is_some() {
            return;
        }
        let why = match self.worker.take().map(|h| h.join()) {
            Some(Err(panic)) => panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "a panic".into()),
            _ => "it stopped".into(),
        };
        let message = format!("the engine stopped ({why}); the last saved file is intact");
        self.notify(message.clone());
        self.engine_stopped = Some(message);
    }

    /// The errors and notices shown so far, oldest first.
    pub fn messages(&self) -> impl Iterator<Item = &str> {
        self.messages.iter().map(|(m, _)| m.as_str())
    }

    pub(crate) fn notify(&mut self, message: String) {
        self.messages.push((message, Instant::now()));
    }

    /// Takes every reply that arrived.
    fn receive(&mut self, ctx: &egui::Context) {
        loop {
            let reply = match self.replies.try_recv() {
                Ok(reply) => reply,
                Err(mpsc::TryRecvError::Empty) => return,
                Err(mpsc::TryRecvError::Disconnected) => return self.engine_gone(),
            };
            match reply {
                Reply::Hover(hit) => self.hover = hit,
                Reply::Mesh(update) => {
                    if let Some(bounds) = update.bounds {
                        self.scene_bounds = Some(bounds);
                        if let Some(camera) = &mut self.camera {
                            camera.set_bounds(bounds);
                        }
                    }
                    if let Ok(viewport) = &mut self.viewport
                        && let Err(why) = viewport.apply(&update)
                    {
                        self.notify(why);
                    }
                }
                Reply::Progress {
                    points,
                    phases,
                    sent,
                } => {
                    self.progress.done += points;
                    self.progress.phases = phases;
                    self.metrics.effect_arrived(sent);
                }
                Reply::Status(status) => {
                    self.status = status;
                    self.status_received = true;
                }
                Reply::StrokeDone(report) => self.last_stroke = Some(*report),
                Reply::Saved(path) => {
                    self.notify(format!("saved {}", path.display()));
                    if self.closing == Some(true) {
                        self.close_confirmed = true;
                        self.closing = None;
                        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    }
                }
                Reply::Opened(path) => {
                    // Framed again when the new mesh's box arrives (it follows).
                    self.camera = None;
                    self.scene_bounds = None;
                    self.save_path = crate::app::save_path_for(&path);
                    self.notify(format!("opened {}", path.display()));
                }
                Reply::Error(message) => self.notify(message),
            }
        }
    }

    /// The layer a duplicate or a patch makes, as the panels set it: the brush's material.
    pub fn new_layer(&self) -> NewLayer {
        NewLayer {
            material: self.tools.material,
            lift_edges: self.tools.lift_edges,
            thickness_edges: self.tools.thickness_edges,
        }
    }

    /// The layer tool's trace drawn so far, in screen points (empty when none is drawn).
    pub fn trace_outline(&self) -> &[egui::Pos2] {
        self.pointer.trace_outline()
    }

    /// The stroke the brush panel describes, with the modifiers held at its start.
    fn stroke_settings(
        &self,
        modifiers: egui::Modifiers,
    ) -> Result<crate::brush::StrokeSettings, String> {
        let tools = &self.tools;
        let mut kind = tools.brush.kind;
        if modifiers.shift {
            kind = BrushKind::Smooth;
        }
        let paints =
            kind == BrushKind::Paint || (tools.paint_while_sculpting && kind != BrushKind::Mask);
        let stencil = tools.stencil.map(|choice| {
            let second = crate::material::preset(choice.second).map_or(Brdf::CLAY, |m| m.brdf);
            Arc::new(crate::brush::Stencil::pattern(
                choice.pattern,
                tools.material,
                second,
                choice.tile,
            ))
        });
        let paint = paints.then(|| crate::brush::Paint {
            opacity: tools.opacity,
            stencil,
            ..crate::brush::Paint::material(tools.material)
        });
        let layers: Vec<u32> = (0..self.status.layers.len() as u32)
            .filter(|&l| self.status.layers[l as usize].1.active)
            .collect();
        if layers.is_empty() {
            return Err("no layer is active: tick one in the Layers panel".into());
        }
        let fuse = layers
            .iter()
            .copied()
            .filter(|&l| self.status.layers[l as usize].1.policy == ProximityPolicy::Fuse)
            .collect();
        let settings = crate::brush::StrokeSettings {
            brush: crate::brush::Brush {
                kind,
                radius: tools.brush.radius,
                strength: tools.brush.strength,
                falloff: tools.brush.falloff,
                invert: tools.brush.invert != modifiers.command,
            },
            paint,
            layers,
            spacing: tools.brush.spacing,
            symmetry: tools
                .symmetry_x
                .then(|| crate::brush::Mirror::new(self.status.centre, glam::Vec3::X))
                .flatten(),
            fuse,
        };
        settings.check(self.status.extent.max(1e-6))?;
        Ok(settings)
    }
}

impl eframe::App for SlayerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let frame_start = Instant::now();
        self.receive(ui.ctx());
        self.ask_before_closing(ui.ctx());
        input::keys(self, ui.ctx());
        panels::status_bar(self, ui);
        // The panels' ranges come from the mesh: they wait for the engine's first report.
        if self.status_received {
            panels::tools_panel(self, ui);
            panels::document_panel(self, ui);
        }
        egui::CentralPanel::default().show(ui, |ui| self.viewport_ui(ui));
        panels::overlays(self, ui.ctx());
        replay::step(self, ui.ctx());
        let uploaded = self.viewport.as_mut().map_or(0, |v| v.take_uploaded());
        let from_engine = self.viewport.as_ref().is_ok_and(|v| v.draws_from_engine());
        let pending = self.progress.done < self.progress.sent;
        let activity = self.pointer.activity(pending);
        self.metrics
            .frame_done(frame_start, activity, (uploaded, from_engine));
        if !self.idle() {
            ui.ctx().request_repaint();
        }
    }

    fn on_exit(&mut self) {
        // Dropping the sender ends the worker's loop; wait so a save in flight completes.
        let (closed, _) = mpsc::channel();
        self.commands = closed;
        if let Some(handle) = self.worker.take() {
            let _ = handle.join();
        }
        self.metrics
            .report(self.metrics_path.as_deref(), self.started);
    }
}

impl SlayerApp {
    fn viewport_ui(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
        self.viewport_rect = Some(rect);
        // Framed once the panels are laid out (they wait for the status): the viewport's shape
        // is then final.
        if self.camera.is_none()
            && self.status_received
            && let Some(bounds) = self.scene_bounds
        {
            self.camera = Some(OrbitCamera::framing(bounds, self.aspect()));
        }
        let pixels_per_point = ui.ctx().pixels_per_point();
        let size = (
            (rect.width() * pixels_per_point).round() as u32,
            (rect.height() * pixels_per_point).round() as u32,
        );
        input::pointer(self, ui, rect, &response);
        let aspect = rect.width() / rect.height().max(1.0);
        let (Ok(viewport), Some(renderer), Some(camera)) =
            (&mut self.viewport, &self.renderer, &self.camera)
        else {
            let why = match &self.viewport {
                Err(why) => why.clone(),
                Ok(_) => "loading…".into(),
            };
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                why,
                egui::FontId::proportional(16.0),
                ui.visuals().text_color(),
            );
            return;
        };
        viewport.render(
            &mut renderer.write(),
            size,
            &camera.view(aspect),
            &self.tools.view,
        );
        if let Some(texture) = viewport.texture {
            let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
            ui.painter().image(texture, rect, uv, egui::Color32::WHITE);
        }
        panels::brush_circle(self, ui.painter(), rect);
        panels::trace_outline(self, ui.painter());
    }
}

/// Where Ctrl-S saves a document opened from `path`: the session itself, or a `.slayer` beside
/// the mesh file (the mesh file is never overwritten).
pub fn save_path_for(path: &std::path::Path) -> PathBuf {
    if crate::session::is_session_path(path) {
        path.to_path_buf()
    } else {
        path.with_extension("slayer")
    }
}

/// Runs the app in a window until it is closed; on `shared`, the engine's device, when the
/// engine runs on the GPU.
pub fn run(setup: AppSetup, window: [f32; 2], shared: Option<SharedDevice>) -> Result<(), String> {
    let shares_engine_device = shared.is_some();
    let mut wgpu_options = egui_wgpu::WgpuConfiguration::default();
    if let Some(shared) = shared {
        wgpu_options.wgpu_setup = egui_wgpu::WgpuSetup::Existing(egui_wgpu::WgpuSetupExisting {
            instance: shared.instance,
            adapter: shared.adapter,
            device: shared.device,
            queue: shared.queue,
        });
    }
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(window)
            .with_title("slayer"),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options,
        ..Default::default()
    };
    eframe::run_native(
        "slayer",
        options,
        Box::new(move |cc| {
            let app = SlayerApp::on_device(cc, setup, shares_engine_device);
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| format!("the window could not open: {e}"))
}
