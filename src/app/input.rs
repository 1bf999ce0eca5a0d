//! Pointer and keyboard, in the conventions of Blender's sculpt mode: a drag on the mesh is a
//! stroke (Ctrl inverts, Shift smooths), a drag on the background or with the middle button
//! orbits (Shift+middle pans), the wheel zooms, F / Shift-F then a move sets the radius /
//! strength. Every pointer event of a stroke becomes a sample, not only the frame's last.

use std::time::Instant;

use eframe::egui::{self, Event, Key, Modifiers, PointerButton, Pos2, Rect};
use glam::Vec2;

use super::pick::Ray;
use super::worker::{Command, LayerTool, StrokePoint};
use super::{SlayerApp, Trace};
use crate::brush::BrushKind;

/// What a drag is doing.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
enum Gesture {
    #[default]
    None,
    Stroke,
    /// A layer tool (cut, patch) traced on the surface: the rays gather in `PointerState`.
    Trace,
    Orbit,
    Pan,
    /// F or Shift-F: the pointer's horizontal travel sets the value until a click or release.
    Adjust {
        strength: bool,
        origin: Pos2,
        start: f32,
    },
}

/// What the frame was busy with, for the frame measurements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Activity {
    Idle,
    Stroking,
    Orbiting,
}

#[derive(Debug, Clone, Default)]
pub struct PointerState {
    gesture: Gesture,
    last: Option<Pos2>,
    /// Pen pressure of the last touch event (1 for a mouse).
    pressure: Option<f32>,
    /// The camera turned this frame.
    moved_camera: bool,
    /// The replay's orbit (counted as orbiting).
    pub orbiting_by_replay: bool,
    /// The rays of a layer tool's trace so far.
    trace: Vec<Ray>,
    /// The same trace in screen points, drawn over the viewport while it is traced.
    outline: Vec<Pos2>,
}

impl PointerState {
    pub fn stroking(&self) -> bool {
        self.gesture == Gesture::Stroke
    }

    pub fn trace_outline(&self) -> &[Pos2] {
        &self.outline
    }

    /// The trace's rays, leaving no trace drawn.
    fn take_trace(&mut self) -> Vec<Ray> {
        self.outline.clear();
        std::mem::take(&mut self.trace)
    }

    /// What this frame did (`samples_pending`: the engine has stroke samples to run, the
    /// replay's included); clears the per-frame marks.
    pub fn activity(&mut self, samples_pending: bool) -> Activity {
        let moved = std::mem::take(&mut self.moved_camera);
        if self.gesture == Gesture::Stroke || samples_pending {
            Activity::Stroking
        } else if moved || self.orbiting_by_replay {
            Activity::Orbiting
        } else {
            Activity::Idle
        }
    }
}

/// The frame's pointer events over the viewport `rect`.
pub fn pointer(app: &mut SlayerApp, ui: &egui::Ui, rect: Rect, response: &egui::Response) {
    let events = ui.input(|i| i.events.clone());
    let mut points = Vec::new();
    let arrived = Instant::now();
    for event in events {
        match event {
            Event::Touch { force, phase, .. } => {
                // A lifted pen's last force must not weigh on the next (mouse) stroke.
                let lifted = matches!(phase, egui::TouchPhase::End | egui::TouchPhase::Cancel);
                app.pointer.pressure = if lifted { None } else { force };
            }
            Event::PointerButton {
                pos,
                button,
                pressed,
                modifiers,
            } => {
                let on_viewport = response.hovered() || response.contains_pointer();
                button_event(
                    app,
                    rect,
                    on_viewport,
                    pos,
                    button,
                    pressed,
                    modifiers,
                    &mut points,
                );
            }
            Event::PointerMoved(pos) => {
                moved(app, rect, pos, &mut points);
                app.pointer.last = Some(pos);
            }
            // The release may never come: the stroke ends here, a trace is dropped.
            Event::PointerGone | Event::WindowFocused(false) => {
                match app.pointer.gesture {
                    Gesture::Stroke => end_stroke(app, &mut points),
                    Gesture::Trace => drop(app.pointer.take_trace()),
                    _ => {}
                }
                app.pointer.gesture = Gesture::None;
                app.hover = None;
            }
            Event::MouseWheel { delta, unit, .. } if response.hovered() => {
                let steps = match unit {
                    egui::MouseWheelUnit::Point => delta.y / 50.0,
                    egui::MouseWheelUnit::Line => delta.y,
                    egui::MouseWheelUnit::Page => delta.y * 10.0,
                };
                if let Some(camera) = &mut app.camera {
                    camera.zoom(steps.clamp(-10.0, 10.0));
                    app.pointer.moved_camera = true;
                    app.hover = None;
                }
            }
            _ => {}
        }
    }
    if !points.is_empty() {
        app.progress.sent += points.len();
        app.send(Command::Points {
            points,
            sent: arrived,
        });
    }
}

#[allow(clippy::too_many_arguments)]
fn button_event(
    app: &mut SlayerApp,
    rect: Rect,
    on_viewport: bool,
    pos: Pos2,
    button: PointerButton,
    pressed: bool,
    modifiers: Modifiers,
    points: &mut Vec<StrokePoint>,
) {
    // A press over a window drawn above the viewport (help, open) is the window's.
    let inside = rect.contains(pos) && on_viewport;
    match (button, pressed, app.pointer.gesture) {
        (PointerButton::Primary, true, Gesture::None) if inside => {
            app.pointer.gesture = match (app.hover.is_some(), app.tools.trace) {
                (true, Some(_)) => {
                    app.pointer.trace = ray_at(app, rect, pos).into_iter().collect();
                    app.pointer.outline = vec![pos];
                    Gesture::Trace
                }
                (true, None) => begin_stroke(app, modifiers, rect, pos, points),
                (false, _) => Gesture::Orbit,
            };
        }
        (PointerButton::Primary, false, gesture) => {
            match gesture {
                Gesture::Stroke => end_stroke(app, points),
                Gesture::Trace => end_trace(app),
                _ => {}
            }
            app.pointer.gesture = Gesture::None;
        }
        (PointerButton::Middle, true, Gesture::None) if inside => {
            app.pointer.gesture = if modifiers.shift {
                Gesture::Pan
            } else {
                Gesture::Orbit
            };
        }
        (PointerButton::Middle, false, Gesture::Orbit | Gesture::Pan) => {
            app.pointer.gesture = Gesture::None;
        }
        (
            PointerButton::Secondary,
            true,
            Gesture::Adjust {
                strength, start, ..
            },
        ) => {
            // Right click cancels, as in Blender.
            set_adjusted(app, strength, start);
            app.pointer.gesture = Gesture::None;
        }
        _ => {}
    }
}

/// Sends the stroke's last points and its end; the surface under the pointer is picked again
/// when it next moves.
fn end_stroke(app: &mut SlayerApp, points: &mut Vec<StrokePoint>) {
    if !points.is_empty() {
        app.progress.sent += points.len();
        app.send(Command::Points {
            points: std::mem::take(points),
            sent: Instant::now(),
        });
    }
    app.send(Command::End);
    app.hover = None;
}

/// Hands the traced rays to the engine for the chosen layer tool.
fn end_trace(app: &mut SlayerApp) {
    let rays = app.pointer.take_trace();
    let tool = match app.tools.trace {
        Some(Trace::Cut) => LayerTool::Cut,
        Some(Trace::Patch) => LayerTool::Patch(app.new_layer()),
        None => return,
    };
    app.send(Command::Trace(tool, rays));
    app.hover = None;
}

fn begin_stroke(
    app: &mut SlayerApp,
    modifiers: Modifiers,
    rect: Rect,
    pos: Pos2,
    points: &mut Vec<StrokePoint>,
) -> Gesture {
    match app.stroke_settings(modifiers) {
        Ok(settings) => {
            app.send(Command::Begin(settings));
            if let Some(point) = ray_point(app, rect, pos) {
                points.push(point);
            }
            Gesture::Stroke
        }
        Err(why) => {
            app.notify(why);
            Gesture::None
        }
    }
}

fn moved(app: &mut SlayerApp, rect: Rect, pos: Pos2, points: &mut Vec<StrokePoint>) {
    let delta = app
        .pointer
        .last
        .map_or(Vec2::ZERO, |last| Vec2::new(pos.x - last.x, pos.y - last.y));
    match app.pointer.gesture {
        Gesture::Stroke => points.extend(ray_point(app, rect, pos)),
        Gesture::Trace => {
            let ray = ray_at(app, rect, pos);
            app.pointer.trace.extend(ray);
            app.pointer.outline.push(pos);
        }
        Gesture::Orbit => {
            if let Some(camera) = &mut app.camera {
                camera.orbit(delta);
                app.pointer.moved_camera = true;
                app.hover = None;
            }
        }
        Gesture::Pan => {
            if let Some(camera) = &mut app.camera {
                camera.pan(delta, rect.height(), rect.aspect_ratio());
                app.pointer.moved_camera = true;
                app.hover = None;
            }
        }
        Gesture::Adjust {
            strength,
            origin,
            start,
        } => {
            let travel = pos.x - origin.x;
            let value = if strength {
                (start + travel / 300.0).clamp(0.0, 1.0)
            } else {
                // The radius follows the pointer: world units per point at the target depth.
                let per_point = app.camera.map_or(0.0, |c| c.world_per_pixel(rect.height()));
                (start + travel * per_point).max(0.25 * app.status.edge_length.max(1e-6))
            };
            set_adjusted(app, strength, value);
        }
        Gesture::None => {
            if rect.contains(pos)
                && let Some(camera) = &app.camera
            {
                let ray = camera.ray(local(rect, pos), Vec2::new(rect.width(), rect.height()));
                app.send(Command::Hover(ray));
            } else {
                app.hover = None;
            }
        }
    }
}

fn set_adjusted(app: &mut SlayerApp, strength: bool, value: f32) {
    if strength {
        app.tools.brush.strength = value;
    } else {
        app.tools.brush.radius = value;
    }
}

fn local(rect: Rect, pos: Pos2) -> Vec2 {
    Vec2::new(pos.x - rect.min.x, pos.y - rect.min.y)
}

fn ray_point(app: &SlayerApp, rect: Rect, pos: Pos2) -> Option<StrokePoint> {
    Some(StrokePoint::Ray {
        ray: ray_at(app, rect, pos)?,
        pressure: app.pointer.pressure.unwrap_or(1.0),
    })
}

/// The brushes a number key picks (mask is M; the sweeps and trim are in the Brush panel's
/// list only).
pub(super) const BRUSH_KEYS: [(Key, BrushKind); 10] = [
    (Key::Num1, BrushKind::Draw),
    (Key::Num2, BrushKind::Inflate),
    (Key::Num3, BrushKind::Deflate),
    (Key::Num4, BrushKind::Grab),
    (Key::Num5, BrushKind::Smooth),
    (Key::Num6, BrushKind::Flatten),
    (Key::Num7, BrushKind::Pinch),
    (Key::Num8, BrushKind::Crease),
    (Key::Num9, BrushKind::Twist),
    (Key::Num0, BrushKind::Paint),
];
/// The camera's ray through `pos`.
fn ray_at(app: &SlayerApp, rect: Rect, pos: Pos2) -> Option<Ray> {
    let camera = app.camera.as_ref()?;
    Some(camera.ray(local(rect, pos), Vec2::new(rect.width(), rect.height())))
}

/// The key map (ignored while a text field has the keyboard).
pub fn keys(app: &mut SlayerApp, ctx: &egui::Context) {
    if ctx.egui_wants_keyboard_input() {
        return;
    }
    let command = |key| (Modifiers::COMMAND, key);
    let pressed =
        |(modifiers, key): (Modifiers, Key)| ctx.input_mut(|i| i.consume_key(modifiers, key));
    if pressed((Modifiers::COMMAND | Modifiers::SHIFT, Key::Z)) || pressed(command(Key::Y)) {
        app.send(Command::Redo);
    } else if pressed(command(Key::Z)) {
        app.send(Command::Undo);
    }
    if pressed(command(Key::S)) {
        app.send(Command::Save(app.save_path.clone()));
    }
    if pressed(command(Key::O)) {
        app.open_path = Some(String::new());
    }
    if pressed(command(Key::I)) {
        app.send(Command::InvertMask);
    }
    if pressed((Modifiers::ALT, Key::M)) {
        app.send(Command::ClearMask);
    } else if pressed((Modifiers::NONE, Key::M)) {
        app.tools.brush.kind = BrushKind::Mask;
    }
    let adjust = |strength: bool, app: &mut SlayerApp| {
        let origin = app.pointer.last.unwrap_or_default();
        let start = if strength {
            app.tools.brush.strength
        } else {
            app.tools.brush.radius
        };
        app.pointer.gesture = Gesture::Adjust {
            strength,
            origin,
            start,
        };
    };
    // Not while a drag is going on: its release must end what it began.
    let free = app.pointer.gesture == Gesture::None;
    if pressed((Modifiers::SHIFT, Key::F)) && free {
        adjust(true, app);
    } else if pressed((Modifiers::NONE, Key::F)) && free {
        adjust(false, app);
    }
    if pressed((Modifiers::NONE, Key::OpenBracket)) {
        app.tools.brush.radius *= 0.9;
    }
    if pressed((Modifiers::NONE, Key::CloseBracket)) {
        app.tools.brush.radius /= 0.9;
    }
    if pressed((Modifiers::NONE, Key::X)) {
        app.tools.symmetry_x = !app.tools.symmetry_x;
    }
    for (key, kind) in BRUSH_KEYS {
        if pressed((Modifiers::NONE, key)) {
            app.tools.brush.kind = kind;
        }
    }
    if pressed((Modifiers::NONE, Key::Home)) || pressed((Modifiers::NONE, Key::Period)) {
        let aspect = app.aspect();
        if let Some(camera) = &mut app.camera {
            camera.frame_all(aspect);
        }
    }
    if pressed((Modifiers::NONE, Key::H)) || pressed((Modifiers::NONE, Key::F1)) {
        app.help = !app.help;
    }
    if pressed((Modifiers::NONE, Key::Escape)) {
        app.help = false;
        if let Gesture::Adjust {
            strength, start, ..
        } = app.pointer.gesture
        {
            set_adjusted(app, strength, start);
            app.pointer.gesture = Gesture::None;
        }
        if app.pointer.gesture == Gesture::Trace {
            drop(app.pointer.take_trace());
            app.pointer.gesture = Gesture::None;
        }
    }
}

/// The key map as the help overlay lists it.
pub const KEY_MAP: &[(&str, &str)] = &[
    ("drag on the mesh", "stroke with the current brush"),
    (
        "drag with cut / patch chosen",
        "trace the layer tool (Esc while dragging drops the trace)",
    ),
    ("Ctrl + drag", "stroke inverted"),
    ("Shift + drag", "smooth"),
    ("drag on the background, middle drag", "orbit"),
    ("Shift + middle drag", "pan"),
    ("wheel", "zoom"),
    (
        "F, then move",
        "brush radius (click to set, right click / Esc to cancel)",
    ),
    ("Shift-F, then move", "brush strength"),
    ("[  ]", "smaller / larger radius"),
    (
        "1 … 9, 0",
        "draw, inflate, deflate, grab, smooth, flatten, pinch, crease, twist, paint (sweeps, trim: Brush panel)",
    ),
    ("M", "mask brush"),
    ("Alt-M", "clear the mask"),
    ("Ctrl-I", "invert the mask"),
    ("X", "X symmetry on / off"),
    ("Ctrl-Z, Ctrl-Shift-Z (Ctrl-Y)", "undo, redo"),
    ("Ctrl-S", "save the session (.slayer)"),
    ("Ctrl-O", "open a file"),
    ("Home or .", "frame everything"),
    ("H or F1", "this help"),
];
