//! The app's headless hooks and its frame measurements: a stroke file played through the
//! pointer's path (`--replay`), then an optional save, an orbit of the camera, a screenshot of
//! the window's own pixels and the exit; and [`Metrics`], what `--metrics` writes.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver};
use std::time::{Duration, Instant};

use eframe::egui;
use serde::Serialize;

use super::SlayerApp;
use super::input::Activity;
use super::worker::{Command, StrokePoint};
use crate::brush::Stroke;

/// Replayed samples per second: the rate of a hand's pointer events as egui delivers them
/// (one a frame at 60 Hz), whatever the frame rate, so the latency measured is a user's.
const SAMPLES_PER_SECOND: f64 = 60.0;

/// What the app does after its replay, and where it reports.
#[derive(Debug, Clone, Default)]
pub struct ExitPlan {
    /// Save the session here once the replay is done.
    pub save: Option<PathBuf>,
    /// Orbit the camera this many frames (one degree each) before the screenshot: frames
    /// while orbiting, measured.
    pub spin_frames: u32,
    /// Then wait this many frames, then take the screenshot (if any) and quit.
    pub exit_after_frames: Option<u32>,
    pub screenshot: Option<PathBuf>,
    /// Write the frame measurements here (JSON) when the app closes.
    pub metrics: Option<PathBuf>,
}

enum Phase {
    /// Feeding stroke `stroke` from sample `sample`.
    Strokes {
        stroke: usize,
        sample: usize,
    },
    /// Waiting for the engine to finish what was sent.
    Settling(Receiver<()>),
    Spinning(u32),
    Waiting(u32),
    Screenshot(Receiver<Result<(), String>>),
    Done,
}

pub struct Replay {
    strokes: Vec<Stroke>,
    plan: ExitPlan,
    phase: Phase,
    /// When feeding began, and how many samples were fed since.
    clock: Option<(Instant, usize)>,
}

impl Replay {
    pub fn new(strokes: Vec<Stroke>, plan: ExitPlan) -> Replay {
        Replay {
            strokes,
            plan,
            phase: Phase::Strokes {
                stroke: 0,
                sample: 0,
            },
            clock: None,
        }
    }

    pub fn finished(&self) -> bool {
        matches!(self.phase, Phase::Done)
    }

    /// Nothing to replay, save, spin or quit for: the app is the user's from the start.
    pub fn is_empty(&self) -> bool {
        let plan = &self.plan;
        self.strokes.is_empty()
            && plan.save.is_none()
            && plan.spin_frames == 0
            && plan.exit_after_frames.is_none()
            && plan.screenshot.is_none()
    }
}

/// One frame of the replay and of what follows it.
pub fn step(app: &mut SlayerApp, ctx: &egui::Context) {
    let Some(mut replay) = app.replay.take() else {
        return;
    };
    if app.camera.is_some() {
        replay.phase = advance(app, ctx, &mut replay);
    }
    if !replay.finished() {
        ctx.request_repaint();
    }
    app.replay = Some(replay);
}

fn advance(app: &mut SlayerApp, ctx: &egui::Context, replay: &mut Replay) -> Phase {
    match std::mem::replace(&mut replay.phase, Phase::Done) {
        Phase::Strokes { stroke, sample } => match replay.strokes.get(stroke) {
            Some(current) => {
                if sample == 0 {
                    app.send(Command::Begin(current.settings()));
                }
                let (start, fed) = *replay.clock.get_or_insert((Instant::now(), 0));
                let due = (start.elapsed().as_secs_f64() * SAMPLES_PER_SECOND) as usize;
                let end = (sample + due.saturating_sub(fed).max(1)).min(current.samples.len());
                replay.clock = Some((start, fed + end - sample));
                let points: Vec<StrokePoint> = current.samples[sample..end]
                    .iter()
                    .map(|&s| StrokePoint::Sample(s))
                    .collect();
                app.progress.sent += points.len();
                app.send(Command::Points {
                    points,
                    sent: Instant::now(),
                });
                if end == current.samples.len() {
                    app.send(Command::End);
                    Phase::Strokes {
                        stroke: stroke + 1,
                        sample: 0,
                    }
                } else {
                    Phase::Strokes {
                        stroke,
                        sample: end,
                    }
                }
            }
            None => {
                if let Some(path) = &replay.plan.save {
                    app.send(Command::Save(path.clone()));
                }
                let (answer, wait) = mpsc::channel();
                app.send(Command::Query(Box::new(move |_| {
                    let _ = answer.send(());
                })));
                Phase::Settling(wait)
            }
        },
        Phase::Settling(wait) => match wait.try_recv() {
            Ok(_) => Phase::Spinning(replay.plan.spin_frames),
            Err(mpsc::TryRecvError::Empty) => Phase::Settling(wait),
            Err(mpsc::TryRecvError::Disconnected) => Phase::Spinning(replay.plan.spin_frames),
        },
        Phase::Spinning(0) => match replay.plan.exit_after_frames {
            Some(frames) => Phase::Waiting(frames),
            None => Phase::Done,
        },
        Phase::Spinning(left) => {
            if let Some(camera) = &mut app.camera {
                camera.azimuth = (camera.azimuth + 1.0).rem_euclid(360.0);
            }
            app.pointer.orbiting_by_replay = true;
            Phase::Spinning(left - 1)
        }
        Phase::Waiting(0) => {
            app.pointer.orbiting_by_replay = false;
            match &replay.plan.screenshot {
                Some(path) => Phase::Screenshot(request_screenshot(ctx, path.clone())),
                None => close(app, ctx),
            }
        }
        Phase::Waiting(left) => Phase::Waiting(left - 1),
        Phase::Screenshot(wait) => match wait.try_recv() {
            Ok(Ok(())) => close(app, ctx),
            Ok(Err(why)) => {
                eprintln!("slayer gui: {why}");
                close(app, ctx)
            }
            Err(_) => Phase::Screenshot(wait),
        },
        Phase::Done => Phase::Done,
    }
}

/// Quits without asking: the replay's session was saved (`--save`) or is not wanted.
fn close(app: &mut SlayerApp, ctx: &egui::Context) -> Phase {
    app.close_confirmed = true;
    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    Phase::Done
}

/// Asks for the window's pixels of the next frame; the answer says whether the PNG was written.
fn request_screenshot(ctx: &egui::Context, path: PathBuf) -> Receiver<Result<(), String>> {
    let (done, wait) = mpsc::channel();
    let repaint = ctx.clone();
    ctx.request_screenshot(move |image| {
        let [width, height] = image.size;
        let rgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
        let result = image::RgbaImage::from_raw(width as u32, height as u32, rgba)
            .ok_or_else(|| "the screenshot has the wrong size".to_string())
            .and_then(|png| {
                png.save(&path)
                    .map_err(|e| format!("{}: {e}", path.display()))
            });
        let _ = done.send(result);
        repaint.request_repaint();
    });
    wait
}

/// Frame times, split by what the user was doing, the delay from a pointer event to the frame
/// that shows its effect, and the bytes uploaded per stroking frame.
#[derive(Debug, Clone, Default)]
pub struct Metrics {
    stroking: Vec<f64>,
    orbiting: Vec<f64>,
    /// Milliseconds from a pointer event to the end of the frame that drew its effect.
    latencies: Vec<f64>,
    /// The oldest pointer event whose effect arrived this frame.
    arrived: Option<Instant>,
    uploads: Vec<u64>,
    /// Stroking frames drawn from the GPU backend's own vertex buffers.
    stroking_from_engine: usize,
    /// The longest time one frame's code ran on the UI thread, ms, and the bytes that frame
    /// uploaded (what made it long, when it was the uploads).
    longest_frame_work: f64,
    longest_frame_uploaded: u64,
    last_frame: Option<Instant>,
}

#[derive(Serialize)]
struct Summary {
    frames_stroking: usize,
    fps_stroking: f64,
    frames_orbiting: usize,
    fps_orbiting: f64,
    latency_ms_mean: f64,
    latency_ms_p95: f64,
    latency_samples: usize,
    bytes_uploaded_per_stroking_frame: f64,
    /// Stroking frames whose positions and normals came from the GPU backend's buffers (the
    /// window shares its device), not from rows uploaded for the viewport.
    stroking_frames_drawn_from_engine_buffers: usize,
    longest_frame_work_ms: f64,
    longest_frame_bytes_uploaded: u64,
    peak_memory_mib: Option<f64>,
    seconds: f64,
}

impl Metrics {
    pub(crate) fn effect_arrived(&mut self, sent: Instant) {
        self.arrived = Some(self.arrived.map_or(sent, |a| a.min(sent)));
    }

    /// `uploaded`: bytes the frame wrote to the viewport's buffers, and whether it drew
    /// positions and normals from the GPU backend's own buffers.
    pub(crate) fn frame_done(
        &mut self,
        start: Instant,
        activity: Activity,
        (uploaded, from_engine): (u64, bool),
    ) {
        let now = Instant::now();
        self.longest_frame_work = self.longest_frame_work.max(ms(now.duration_since(start)));
        if let Some(last) = self.last_frame {
            let interval = ms(now.duration_since(last));
            match activity {
                Activity::Stroking => {
                    self.stroking.push(interval);
                    self.uploads.push(uploaded);
                    self.stroking_from_engine += usize::from(from_engine);
                }
                Activity::Orbiting => self.orbiting.push(interval),
                Activity::Idle => {}
            }
        }
        if let Some(sent) = self.arrived.take() {
            self.latencies.push(ms(now.duration_since(sent)));
        }
        self.last_frame = Some(now);
    }

    fn summary(&self, started: Instant) -> Summary {
        let fps = |frames: &[f64]| {
            let total: f64 = frames.iter().sum();
            if total > 0.0 {
                1000.0 * frames.len() as f64 / total
            } else {
                0.0
            }
        };
        let mut latencies = self.latencies.clone();
        latencies.sort_by(f64::total_cmp);
        let mean = |v: &[f64]| {
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        let p95 = latencies
            .get(((latencies.len() as f64 * 0.95).ceil() as usize).saturating_sub(1))
            .copied()
            .unwrap_or(0.0);
        let uploads: Vec<f64> = self.uploads.iter().map(|&b| b as f64).collect();
        Summary {
            frames_stroking: self.stroking.len(),
            fps_stroking: fps(&self.stroking),
            frames_orbiting: self.orbiting.len(),
            fps_orbiting: fps(&self.orbiting),
            latency_ms_mean: mean(&latencies),
            latency_ms_p95: p95,
            latency_samples: latencies.len(),
            bytes_uploaded_per_stroking_frame: mean(&uploads),
            stroking_frames_drawn_from_engine_buffers: self.stroking_from_engine,
            longest_frame_work_ms: self.longest_frame_work,
            longest_frame_bytes_uploaded: self.longest_frame_uploaded,
            peak_memory_mib: crate::memory::peak_resident_bytes().map(|b| b as f64 / 1048576.0),
            seconds: started.elapsed().as_secs_f64(),
        }
    }

    /// Prints the summary, and writes it as JSON to `path` when given.
    pub(crate) fn report(&self, path: Option<&Path>, started: Instant) {
        let summary = self.summary(started);
        let json = serde_json::to_string_pretty(&summary).expect("numbers serialize");
        if let Some(path) = path
            && let Err(e) = std::fs::write(path, &json)
        {
            eprintln!("slayer gui: {}: {e}", path.display());
        }
    }
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}
