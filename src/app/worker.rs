//! The engine thread: it owns the [`Session`] and the [`Pipeline`], takes the UI's commands
//! from a channel and answers with what changed, so the UI never waits for a stroke.
//!
//! A stroke is `Begin`, any number of `Points` (each pointer event's ray, or a replayed 3-D
//! sample), then `End`. Points that queued while a call ran go into the next
//! `add_samples` call together: the engine resamples across calls, so how the points were
//! batched changes nothing in the mesh, only how often the UI hears about it.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender};
use std::time::Instant;

use glam::Vec3;

use super::pick::{Hit, Picker, Ray};
use super::upload::{MeshUpdate, Mirror};
use crate::brush::{Sample, StrokeSettings};
use crate::mesh::{Brdf, LayerId, Mesh};
use crate::pipeline::{PhaseTimes, Pipeline, Remeshing, StrokeInProgress, StrokeReport};
use crate::session::{LayerSettings, Session};
use crate::tools::{CutSettings, DeleteTarget, DuplicateSettings, Selection, selected_faces};

/// While a batch of points runs, the UI hears what changed at least this often, so the
/// picture follows the stroke even when the engine is behind the pointer.
const FLUSH_INTERVAL: std::time::Duration = std::time::Duration::from_millis(30);

/// One pointer event of a stroke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StrokePoint {
    /// The pointer's ray; the engine picks it onto the surface as the mesh is then.
    Ray { ray: Ray, pressure: f32 },
    /// A sample given in 3-D (a replayed stroke file).
    Sample(Sample),
}

pub enum Command {
    /// Pick under the pointer (answered with [`Reply::Hover`]).
    Hover(Ray),
    Begin(StrokeSettings),
    /// `sent` is when the oldest of the points arrived: it comes back with their effect.
    Points {
        points: Vec<StrokePoint>,
        sent: Instant,
    },
    End,
    Undo,
    Redo,
    SetLayer(LayerId, LayerSettings),
    RenameLayer(LayerId, String),
    /// Copies the layer's masked part (all of it where nothing is masked) into a new layer
    /// lifted off it.
    DuplicateLayer(LayerId, NewLayer),
    DeleteLayer(LayerId),
    /// A layer tool traced on the surface: the pointer's rays over one drag.
    Trace(LayerTool, Vec<Ray>),
    ClearMask,
    InvertMask,
    Save(PathBuf),
    /// Replaces the session with a file's (the mesh is repaired as `slayer check` would).
    Open(PathBuf),
    /// Remesh after each stroke, or not.
    Remeshing(bool),
    /// Runs once every earlier command is done, on the session as they left it (tests, the
    /// replay's end).
    Query(Box<dyn FnOnce(&Session) + Send>),
}

/// A layer tool a drag on the mesh traces instead of a stroke.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LayerTool {
    /// Cut the active layers open along the trace.
    Cut,
    /// A new layer filling the closed trace.
    Patch(NewLayer),
}

/// What a duplicate or a patch makes: a layer in `material`, lifted `lift_edges` edge lengths
/// off the surface it comes from, and `thickness_edges` thick (0: an open sheet; more: a closed
/// shell).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewLayer {
    pub material: Brdf,
    pub lift_edges: f32,
    pub thickness_edges: f32,
}

impl NewLayer {
    /// The library's settings for this layer on `mesh`, in its edge length.
    fn settings(&self, mesh: &Mesh, name: &str) -> DuplicateSettings {
        let mut settings = DuplicateSettings::for_mesh(mesh, name, self.material);
        settings.offset = self.lift_edges * settings.edge;
        settings.thickness =
            (self.thickness_edges > 0.0).then_some(self.thickness_edges * settings.edge);
        settings
    }
}

/// The document as the panels show it.
#[derive(Debug, Clone, Default)]
pub struct Status {
    pub faces: usize,
    pub vertices: usize,
    pub layers: Vec<(String, LayerSettings)>,
    pub history: Vec<String>,
    /// Entries of `history` that are done (the rest can be redone).
    pub done: usize,
    pub edge_length: f32,
    pub extent: f32,
    pub centre: Vec3,
    pub backend: String,
    /// Something changed since the session was opened or last saved.
    pub unsaved: bool,
}

pub enum Reply {
    Hover(Option<Hit>),
    Mesh(MeshUpdate),
    /// Points done, the engine's phase times for them, and when the oldest was sent.
    Progress {
        points: usize,
        phases: PhaseTimes,
        sent: Instant,
    },
    Status(Status),
    /// A stroke ended: its counts and phase times, remeshing included.
    StrokeDone(Box<StrokeReport>),
    Saved(PathBuf),
    Opened(PathBuf),
    /// A refused command, or a stroke that stopped: the mesh keeps what the stroke did before
    /// the failed call (that call changes nothing), remeshed as any stroke's end.
    Error(String),
}

/// The engine thread's state.
pub struct Worker {
    session: Session,
    /// Edits so far, and how many there were at the last save (or open).
    revision: u64,
    saved_revision: u64,
    pipeline: Pipeline,
    /// The GPU's failure was reported.
    gpu_failure_said: bool,
    picker: Picker,
    /// What the viewport holds.
    mirror: Mirror,
    /// The viewport draws with the GPU backend's device: it draws positions and normals
    /// from the backend's own buffers.
    viewport_on_engine_device: bool,
    link: Link,
}

impl Worker {
    pub fn new(
        session: Session,
        pipeline: Pipeline,
        commands: Receiver<Command>,
        replies: Sender<Reply>,
        wake: Box<dyn Fn() + Send>,
        viewport_on_engine_device: bool,
    ) -> Worker {
        Worker {
            picker: Picker::default(),
            mirror: Mirror::default(),
            viewport_on_engine_device,
            revision: 0,
            saved_revision: 0,
            gpu_failure_said: false,
            session,
            pipeline,
            link: Link {
                commands,
                pending: VecDeque::new(),
                replies,
                wake,
            },
        }
    }

    /// Serves commands until the UI hangs up.
    pub fn run(mut self) {
        // The undo copy, on this thread now rather than in the first stroke.
        self.session.prepare_history();
        self.rebuild_picker();
        self.send_changes();
        self.send_status();
        self.prepare_pipeline();
        while let Some(command) = self.link.next() {
            self.serve(command);
        }
    }

    fn serve(&mut self, command: Command) {
        match command {
            Command::Hover(ray) => {
                let ray = self.link.latest_hover(ray);
                let hit = self.picker.pick(self.session.mesh(), &ray);
                self.link.reply(Reply::Hover(hit));
            }
            Command::Begin(settings) => self.stroke(settings),
            // Points or an end without a begin: a stroke that was refused.
            Command::Points { .. } | Command::End => {}
            Command::Undo => {
                let stepped = self.session.undo().is_some();
                self.after_edit(stepped);
            }
            Command::Redo => {
                let stepped = self.session.redo().is_some();
                self.after_edit(stepped);
            }
            Command::SetLayer(layer, settings) => {
                let result = self.session.set_layer(layer, settings);
                self.rebuild_picker();
                self.after_refusable(result.map(|_| ()).map_err(|e| e.to_string()));
            }
            Command::RenameLayer(layer, name) => {
                let result = self.session.rename_layer(layer, &name);
                self.after_refusable(result.map(|_| ()).map_err(|e| e.to_string()));
            }
            Command::DuplicateLayer(layer, new_layer) => {
                let result = self.duplicate(layer, new_layer);
                self.after_tool(result);
            }
            Command::Trace(tool, rays) => {
                let result = self.trace(tool, &rays);
                self.after_tool(result);
            }
            Command::DeleteLayer(layer) => {
                let result = self.session.delete(DeleteTarget::Layer(layer));
                self.after_tool(result.map(|_| ()).map_err(|e| e.to_string()));
            }
            Command::ClearMask => {
                self.session.clear_mask();
                self.after_edit(true);
            }
            Command::InvertMask => {
                self.session.invert_mask();
                self.after_edit(true);
            }
            Command::Save(path) => match crate::session::save(&self.session, &path, true) {
                Ok(()) => {
                    // A mesh file (not `.slayer`) keeps the mesh, not the document: still
                    // counts as saved, as the user chose that file.
                    self.saved_revision = self.revision;
                    self.link.reply(Reply::Saved(path));
                    self.send_status();
                }
                Err(e) => self
                    .link
                    .reply(Reply::Error(format!("{}: {e}", path.display()))),
            },
            Command::Open(path) => self.open(path),
            Command::Remeshing(on) => self.pipeline.set_remeshing(if on {
                Remeshing::AfterStroke
            } else {
                Remeshing::Off
            }),
            Command::Query(question) => question(&self.session),
        }
    }

    fn open(&mut self, path: PathBuf) {
        match crate::session::open_with(&path, &Default::default()) {
            Ok((session, report)) => {
                self.session = session;
                // Another mesh, with its own edge length.
                self.pipeline.forget_mesh();
                self.session.prepare_history();
                // The file as opened is saved: `after_edit` counts the change of document.
                self.saved_revision = self.revision + 1;
                for line in report.lines() {
                    self.link
                        .reply(Reply::Error(format!("{}: {line}", path.display())));
                }
                self.link.reply(Reply::Opened(path));
                self.after_edit(true);
                self.prepare_pipeline();
            }
            Err(e) => self
                .link
                .reply(Reply::Error(format!("{}: {e}", path.display()))),
        }
    }

    /// The grid, the GPU's copy of the mesh and its compiled kernels, built now that the mesh
    /// is on screen rather than in the first stroke (which would stall for them). A failure
    /// here is the first stroke's too, and reported there.
    fn prepare_pipeline(&mut self) {
        let _ = self.pipeline.prepare(self.session.mesh());
    }

    fn after_edit(&mut self, changed: bool) {
        if changed {
            self.revision += 1;
            self.rebuild_picker();
            self.send_changes();
        }
        self.send_status();
    }

    fn duplicate(&mut self, layer: LayerId, new_layer: NewLayer) -> Result<(), String> {
        let mesh = self.session.mesh();
        let masked = selected_faces(mesh, Selection::Masked(layer)).is_ok();
        let selection = if masked {
            Selection::Masked(layer)
        } else {
            Selection::Layer(layer)
        };
        let name = mesh
            .layer_names()
            .get(layer as usize)
            .cloned()
            .unwrap_or_default();
        let settings = new_layer.settings(mesh, &format!("{name} copy"));
        let result = self.session.duplicate(selection, &settings);
        result.map(|_| ()).map_err(|e| e.to_string())
    }

    /// A cut of the active layers along the traced points, or a patch filling them on the
    /// layer the trace began on.
    fn trace(&mut self, tool: LayerTool, rays: &[Ray]) -> Result<(), String> {
        let hits: Vec<Hit> = rays
            .iter()
            .filter_map(|ray| self.picker.pick(self.session.mesh(), ray))
            .collect();
        let Some(first) = hits.first() else {
            return Err("the trace missed the mesh".to_string());
        };
        let mesh = self.session.mesh();
        let layer = mesh.face_layers()[first.face as usize];
        let points: Vec<Vec3> = hits.iter().map(|h| h.point).collect();
        let result = match tool {
            LayerTool::Cut => {
                let settings = CutSettings::for_mesh(mesh, &self.session.active_layers());
                self.session.cut(&points, &settings).map(|_| ())
            }
            LayerTool::Patch(new_layer) => {
                let settings = new_layer.settings(mesh, "patch");
                self.session.patch(&points, layer, &settings).map(|_| ())
            }
        };
        result.map_err(|e| e.to_string())
    }

    /// After a layer tool: a refusal is said, a change shown (layers and topology both).
    fn after_tool(&mut self, result: Result<(), String>) {
        match result {
            Ok(()) => self.after_edit(true),
            Err(why) => self.after_refusable(Err(why)),
        }
    }

    fn after_refusable(&mut self, result: Result<(), String>) {
        match result {
            Ok(()) => self.revision += 1,
            Err(why) => self.link.reply(Reply::Error(why)),
        }
        self.send_status();
    }

    /// One stroke, from its settings to its `End`.
    fn stroke(&mut self, settings: StrokeSettings) {
        let grab = settings.brush.kind.drags();
        let label = crate::session::stroke_label(&settings);
        let visible = self.visible();
        let Worker {
            session,
            pipeline,
            picker,
            mirror,
            viewport_on_engine_device,
            link,
            ..
        } = self;
        if let Err(why) = Pipeline::check_stroke(session.mesh(), &settings) {
            return self.refuse_stroke(format!("stroke refused: {why}"));
        }
        let mut edit = session.edit(&label);
        // A stroke the pipeline refuses still reads its points up to its end, running none.
        let (mut stroke, mut failure) = match pipeline.begin_stroke(edit.mesh(), settings) {
            Ok(stroke) => (Some(stroke), None),
            Err(e) => (None, Some(format!("stroke refused: {e}"))),
        };
        let mut projector = Projector::default();
        let mut waiting = Waiting::default();
        while let Some(points) = link.next_points(&mut waiting) {
            let stroke = stroke.as_mut().filter(|_| failure.is_none());
            let mut batch = Batch {
                stroke,
                picker,
                mirror,
                viewport_on_engine_device: *viewport_on_engine_device,
                projector: &mut projector,
                visible: &visible,
                grab,
            };
            if let Err(why) = batch.run(&points, link) {
                failure = Some(why);
            }
        }
        match stroke.map(|s| s.finish()) {
            Some(Ok(report)) => link.reply(Reply::StrokeDone(Box::new(report))),
            Some(Err(e)) => {
                failure.get_or_insert(format!("stroke stopped: {e}"));
            }
            None => {}
        }
        drop(edit);
        if let Some(why) = failure {
            link.reply(Reply::Error(why));
        }
        link.requeue(waiting);
        self.say_if_the_gpu_failed();
        self.after_edit(true);
    }

    /// A stroke refused before it began: it changes nothing, not even the history (whose
    /// undone entries stay redoable); its points are read up to its end and reported done.
    fn refuse_stroke(&mut self, why: String) {
        let mut waiting = Waiting::default();
        while let Some(points) = self.link.next_points(&mut waiting) {
            self.link.reply(Reply::Progress {
                points: points.len(),
                phases: PhaseTimes::default(),
                sent: points[0].1,
            });
        }
        self.link.reply(Reply::Error(why));
        self.link.requeue(waiting);
        self.send_status();
    }

    /// The GPU kernels go on with the CPU's when the GPU fails (a lost device, memory):
    /// the user hears it once.
    fn say_if_the_gpu_failed(&mut self) {
        if let Some(why) = self.pipeline.kernel_failure()
            && !self.gpu_failure_said
        {
            self.gpu_failure_said = true;
            self.link.reply(Reply::Error(format!(
                "the GPU failed ({why}); sculpting goes on on the CPU"
            )));
        }
    }

    fn visible(&self) -> Vec<bool> {
        self.session.layers().iter().map(|l| l.visible).collect()
    }

    fn rebuild_picker(&mut self) {
        self.picker = Picker::build(self.session.mesh(), &self.visible());
    }

    /// Compares the whole mesh with what the viewport holds and sends the difference.
    fn send_changes(&mut self) {
        let mesh = self.session.mesh();
        let engine = (self.viewport_on_engine_device)
            .then(|| self.pipeline.vertex_buffers(mesh))
            .flatten();
        let update = self.mirror.update(mesh, None, true, engine);
        self.link.reply(Reply::Mesh(update));
        // Bringing the GPU's copy up to date can be what fails.
        self.say_if_the_gpu_failed();
    }

    fn send_status(&self) {
        let mesh = self.session.mesh();
        let history = self.session.history();
        let bounds = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
        let status = Status {
            faces: mesh.live_face_count(),
            vertices: mesh.vertex_count(),
            layers: mesh
                .layer_names()
                .iter()
                .cloned()
                .zip(self.session.layers().iter().copied())
                .collect(),
            history: history.entries().iter().map(|e| e.label.clone()).collect(),
            done: history.done(),
            edge_length: mesh.mean_edge_length(),
            extent: (bounds.1 - bounds.0).length(),
            centre: 0.5 * (bounds.0 + bounds.1),
            backend: self.pipeline.name(),
            unsaved: self.revision != self.saved_revision,
        };
        self.link.reply(Reply::Status(status));
    }
}

/// The channels to and from the UI.
struct Link {
    commands: Receiver<Command>,
    /// Commands taken from the channel early (looking for more points) and not yet served.
    pending: VecDeque<Command>,
    replies: Sender<Reply>,
    /// Wakes the UI when a reply is sent.
    wake: Box<dyn Fn() + Send>,
}

impl Link {
    fn next(&mut self) -> Option<Command> {
        self.pending
            .pop_front()
            .or_else(|| self.commands.recv().ok())
    }

    fn reply(&self, reply: Reply) {
        // The UI hung up: nothing left to tell.
        if self.replies.send(reply).is_ok() {
            (self.wake)();
        }
    }

    /// A command already in the channel, unless one taken early still waits in `pending`
    /// (it must go first).
    fn next_queued(&mut self) -> Option<Command> {
        if self.pending.is_empty() {
            self.commands.try_recv().ok()
        } else {
            None
        }
    }

    /// Skips hovers that queued behind this one: only where the pointer is now matters.
    fn latest_hover(&mut self, mut ray: Ray) -> Ray {
        while let Some(command) = self.next_queued() {
            match command {
                Command::Hover(later) => ray = later,
                other => self.pending.push_back(other),
            }
        }
        ray
    }

    /// The next points of the stroke in progress (those of `Points` commands queued right
    /// behind each other joined, each with when its command was sent); `None` at the
    /// stroke's end. Commands that must wait for the end (undo, save) go to `waiting`, and so
    /// does a new stroke's `Begin`, which ends this one (a release the window never saw).
    fn next_points(&mut self, waiting: &mut Waiting) -> Option<Vec<(StrokePoint, Instant)>> {
        loop {
            match self.next()? {
                Command::Points { points, sent } => {
                    let mut all: Vec<_> = points.into_iter().map(|p| (p, sent)).collect();
                    while let Some(command) = self.next_queued() {
                        match command {
                            Command::Points { points, sent } => {
                                all.extend(points.into_iter().map(|p| (p, sent)))
                            }
                            other => self.pending.push_back(other),
                        }
                    }
                    return Some(all);
                }
                Command::End => return None,
                begin @ Command::Begin(_) => {
                    waiting.next_begin = Some(begin);
                    return None;
                }
                Command::Hover(_) => {}
                other => waiting.deferred.push(other),
            }
        }
    }

    /// After a stroke: what waited for its end, then the next stroke.
    fn requeue(&mut self, waiting: Waiting) {
        self.pending.extend(waiting.deferred);
        self.pending.extend(waiting.next_begin);
    }
}

/// Commands that came during a stroke and wait for its end.
#[derive(Default)]
struct Waiting {
    deferred: Vec<Command>,
    next_begin: Option<Command>,
}

/// A stroke's points that arrived together.
struct Batch<'s, 'm> {
    /// `None`: the stroke was refused or stopped; its points run nothing.
    stroke: Option<&'s mut StrokeInProgress<'m>>,
    picker: &'s mut Picker,
    mirror: &'s mut Mirror,
    viewport_on_engine_device: bool,
    projector: &'s mut Projector,
    visible: &'s [bool],
    grab: bool,
}

/// What ran since the UI last heard.
#[derive(Default)]
struct Unsent {
    points: usize,
    oldest: Option<Instant>,
    changed: Vec<u32>,
    topology_changed: bool,
    phases: PhaseTimes,
}

impl Batch<'_, '_> {
    /// Runs the points one `add_samples` call each, picking every ray on the mesh as the
    /// points before it left it: the stroke is then the same however the points were
    /// batched (by the frame rate, by the engine's speed), as a replay needs. The UI hears
    /// what changed every [`FLUSH_INTERVAL`] and at the end; every point is reported done,
    /// those of a stopped stroke too.
    fn run(&mut self, points: &[(StrokePoint, Instant)], link: &Link) -> Result<(), String> {
        let mut unsent = Unsent::default();
        let mut flushed = Instant::now();
        let mut result = Ok(());
        for (k, (point, sent)) in points.iter().enumerate() {
            unsent.points += 1;
            unsent.oldest.get_or_insert(*sent);
            if result.is_ok()
                && let Err(why) = self.step(point, &mut unsent)
            {
                result = Err(why);
            }
            if flushed.elapsed() >= FLUSH_INTERVAL || k + 1 == points.len() {
                self.flush(std::mem::take(&mut unsent), link);
                flushed = Instant::now();
            }
        }
        result
    }

    fn step(&mut self, point: &StrokePoint, unsent: &mut Unsent) -> Result<(), String> {
        let Some(stroke) = self.stroke.as_mut() else {
            return Ok(());
        };
        let Some(sample) = self
            .projector
            .sample(point, stroke.mesh(), self.picker, self.grab)
        else {
            return Ok(());
        };
        let report = match stroke.add_samples(&[sample]) {
            Ok(report) => report,
            Err(e) => {
                self.stroke = None;
                return Err(format!("stroke stopped: {e}"));
            }
        };
        unsent.phases.add(&report.phases);
        let mesh = stroke.mesh();
        if report.topology_changed {
            unsent.topology_changed = true;
            *self.picker = Picker::build(mesh, self.visible);
        } else {
            self.picker.refit(mesh, &report.changed);
        }
        unsent.changed.extend(report.changed);
        Ok(())
    }

    fn flush(&mut self, unsent: Unsent, link: &Link) {
        if let Some(stroke) = &mut self.stroke {
            let engine = (self.viewport_on_engine_device)
                .then(|| stroke.vertex_buffers())
                .flatten();
            let update = self.mirror.update(
                stroke.mesh(),
                Some(&unsent.changed),
                unsent.topology_changed,
                engine,
            );
            if !update.is_empty() {
                link.reply(Reply::Mesh(update));
            }
        }
        link.reply(Reply::Progress {
            points: unsent.points,
            phases: unsent.phases,
            sent: unsent.oldest.unwrap_or_else(Instant::now),
        });
    }
}

/// Turns pointer events into samples: a ray that meets the surface gives the hit; one that
/// misses (the pointer left the mesh), or any ray of a grab, gives the point on the plane
/// facing the eye through the stroke's first hit, as a sculptor's hand expects.
#[derive(Default)]
struct Projector {
    /// The first hit's point and the plane's normal.
    plane: Option<(Vec3, Vec3)>,
}

impl Projector {
    fn sample(
        &mut self,
        point: &StrokePoint,
        mesh: &Mesh,
        picker: &Picker,
        grab: bool,
    ) -> Option<Sample> {
        let (ray, pressure) = match *point {
            StrokePoint::Sample(sample) => return Some(sample),
            StrokePoint::Ray { ray, pressure } => (ray, pressure),
        };
        let on_plane = |(origin, normal): (Vec3, Vec3)| {
            let denominator = ray.direction.dot(normal);
            (denominator.abs() > 1e-6)
                .then(|| ray.at((origin - ray.origin).dot(normal) / denominator))
        };
        let position = match (self.plane, grab) {
            (Some(plane), true) => on_plane(plane)?,
            (plane, _) => match picker.pick(mesh, &ray) {
                Some(hit) => {
                    self.plane.get_or_insert((hit.point, -ray.direction));
                    hit.point
                }
                None => on_plane(plane?)?,
            },
        };
        Some(Sample {
            position,
            pressure: pressure.clamp(0.0, 1.0),
            normal: None,
        })
    }
}
