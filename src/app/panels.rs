//! The panels around the viewport: brush and material on the left, layers and history on the
//! right, the status bar below; the help overlay, the open dialog and the brush circle.

use std::time::Duration;

use eframe::egui::{self, Color32, Painter, Rect, RichText, Stroke as Line, Ui};
use glam::Vec3;

use super::input::BRUSH_KEYS;
use super::worker::Command;
use super::{SlayerApp, StencilChoice, Trace};
use crate::brush::{BrushKind, Falloff, MAX_BLEND_INNER, Pattern};
use crate::material::{PRESETS, linear_to_srgb, srgb_to_linear};
use crate::mesh::Brdf;
use crate::topology::ProximityPolicy;

/// How long a message stays in the status bar.
const MESSAGE_SECONDS: u64 = 8;

pub fn status_bar(app: &mut SlayerApp, ui: &mut Ui) {
    egui::Panel::bottom("status").show(ui, |ui| {
        ui.horizontal_wrapped(|ui| {
            let status = &app.status;
            ui.label(format!(
                "{} · {} faces · {} vertices",
                status.backend, status.faces, status.vertices
            ));
            ui.separator();
            let progress = &app.progress;
            if app.pointer.stroking() || progress.done < progress.sent {
                ui.label(format!(
                    "stroking: {} samples queued",
                    progress.sent - progress.done.min(progress.sent)
                ));
                ui.add(egui::Spinner::new());
            } else {
                ui.label("ready");
            }
            if app.tools.phase_times {
                ui.separator();
                let names = progress
                    .phases
                    .named()
                    .iter()
                    .map(|(name, ms)| format!("{name} {ms:.1}"))
                    .collect::<Vec<_>>()
                    .join(" · ");
                ui.label(format!("last samples, ms: {names}"));
                if let Some(stroke) = &app.last_stroke {
                    ui.separator();
                    ui.label(format!(
                        "last stroke: {} samples, {:.0} ms ({:.0} remeshing), {} moves clamped{}",
                        stroke.samples,
                        stroke.phases.total(),
                        stroke.phases.remesh,
                        stroke.clamped,
                        stroke_bounds_met(stroke)
                    ));
                }
            }
            if let Some(why) = &app.engine_stopped {
                ui.separator();
                ui.label(RichText::new(why).color(Color32::from_rgb(255, 110, 90)));
            }
            app.messages
                .retain(|(_, at)| at.elapsed() < Duration::from_secs(MESSAGE_SECONDS));
            if let Some((message, _)) = app.messages.last() {
                ui.separator();
                ui.label(RichText::new(message).color(Color32::from_rgb(240, 200, 90)));
            }
        });
    });
}

pub fn tools_panel(app: &mut SlayerApp, ui: &mut Ui) {
    egui::Panel::left("tools")
        .default_size(230.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                brush_section(app, ui);
                ui.separator();
                material_section(app, ui);
                ui.separator();
                view_section(app, ui);
            });
        });
}

fn brush_section(app: &mut SlayerApp, ui: &mut Ui) {
    ui.heading("Brush");
    let brush = &mut app.tools.brush;
    egui::ComboBox::from_label("kind")
        .selected_text(brush.kind.name())
        .show_ui(ui, |ui| {
            for kind in BrushKind::ALL {
                let number = BRUSH_KEYS.iter().find(|(_, k)| *k == kind);
                let key = match (number, kind) {
                    (Some((key, _)), _) => format!("  {}", key.symbol_or_name()),
                    (None, BrushKind::Mask) => "  M".into(),
                    (None, _) => String::new(),
                };
                ui.selectable_value(&mut brush.kind, kind, format!("{}{key}", kind.name()));
            }
        });
    trace_choice(app, ui);
    let brush = &mut app.tools.brush;
    let edge = app.status.edge_length.max(1e-6);
    let extent = app.status.extent.max(edge);
    // Not clamped: a radius typed in or set with F stays what the user chose.
    ui.add(
        egui::Slider::new(&mut brush.radius, 0.5 * edge..=0.5 * extent)
            .logarithmic(true)
            .clamping(egui::SliderClamping::Never)
            .text("radius"),
    );
    ui.add(egui::Slider::new(&mut brush.strength, 0.0..=1.0).text("strength"));
    ui.add(egui::Slider::new(&mut brush.spacing, 0.05..=1.0).text("spacing"));
    egui::ComboBox::from_label("falloff")
        .selected_text(brush.falloff.name())
        .show_ui(ui, |ui| {
            let inner = match brush.falloff {
                Falloff::Blend { inner, .. } => inner,
                _ => 0.0,
            };
            for falloff in [
                Falloff::Blend { n: 3, inner },
                Falloff::Smooth,
                Falloff::Sphere,
                Falloff::Linear,
            ] {
                ui.selectable_value(&mut brush.falloff, falloff, falloff.name());
            }
        });
    if let Falloff::Blend { inner, .. } = &mut brush.falloff {
        // Freestyle's inner radius R_i, as a share of the radius.
        ui.add(egui::Slider::new(inner, 0.0..=MAX_BLEND_INNER).text("full-strength core"));
    }
    ui.checkbox(&mut brush.invert, "invert (Ctrl)");
    ui.checkbox(&mut app.tools.symmetry_x, "X symmetry (X)");
    if ui
        .checkbox(&mut app.tools.remesh, "remesh after strokes")
        .changed()
    {
        app.send(Command::Remeshing(app.tools.remesh));
    }
}

fn material_section(app: &mut SlayerApp, ui: &mut Ui) {
    ui.heading("Material");
    let tools = &mut app.tools;
    egui::ComboBox::from_label("preset")
        .selected_text(tools.material_name.as_str())
        .show_ui(ui, |ui| {
            for preset in PRESETS {
                if ui
                    .selectable_label(tools.material_name == preset.name, preset.name)
                    .clicked()
                {
                    tools.material = preset.brdf;
                    tools.material_name = preset.name.into();
                }
            }
        });
    let before = tools.material;
    brdf_editor(ui, &mut tools.material);
    if tools.material != before {
        tools.material_name = "custom".into();
    }
    ui.add(egui::Slider::new(&mut tools.opacity, 0.0..=1.0).text("opacity"));
    stencil_editor(ui, &mut tools.stencil, app.status.edge_length);
    ui.checkbox(&mut tools.paint_while_sculpting, "paint while sculpting");
}

/// No stencil, or a pattern of the material and a second preset, and its tile size.
fn stencil_editor(ui: &mut Ui, stencil: &mut Option<StencilChoice>, edge: f32) {
    let name = stencil.map_or("none", |s| s.pattern.name());
    egui::ComboBox::from_label("stencil")
        .selected_text(name)
        .show_ui(ui, |ui| {
            if ui.selectable_label(stencil.is_none(), "none").clicked() {
                *stencil = None;
            }
            for pattern in Pattern::ALL {
                let chosen = stencil.is_some_and(|s| s.pattern == pattern);
                if ui.selectable_label(chosen, pattern.name()).clicked() {
                    *stencil = Some(StencilChoice {
                        pattern,
                        second: stencil.map_or("bare-metal", |s| s.second),
                        tile: stencil.map_or(8.0 * edge.max(1e-6), |s| s.tile),
                    });
                }
            }
        });
    let Some(choice) = stencil else {
        return;
    };
    egui::ComboBox::from_label("with")
        .selected_text(choice.second)
        .show_ui(ui, |ui| {
            for preset in PRESETS {
                ui.selectable_value(&mut choice.second, preset.name, preset.name);
            }
        });
    let edge = edge.max(1e-6);
    ui.add(
        egui::Slider::new(&mut choice.tile, edge..=200.0 * edge)
            .logarithmic(true)
            .text("tile"),
    );
}

/// Diffuse colour (shown in sRGB, kept linear), grey specular and roughness.
fn brdf_editor(ui: &mut Ui, brdf: &mut Brdf) {
    ui.horizontal(|ui| {
        let mut srgb = brdf.diffuse.map(linear_to_srgb);
        if ui.color_edit_button_rgb(&mut srgb).changed() {
            brdf.diffuse = srgb.map(srgb_to_linear);
        }
        ui.label("diffuse");
    });
    let mut specular = brdf.specular[0];
    if ui
        .add(egui::Slider::new(&mut specular, 0.0..=1.0).text("specular"))
        .changed()
    {
        brdf.specular = [specular; 3];
    }
    ui.add(egui::Slider::new(&mut brdf.roughness, 0.0..=1.0).text("roughness"));
}

fn view_section(app: &mut SlayerApp, ui: &mut Ui) {
    ui.heading("View");
    let view = &mut app.tools.view;
    ui.checkbox(&mut view.wireframe, "wireframe");
    ui.checkbox(&mut view.false_colour, "layer colours");
    ui.checkbox(&mut view.show_mask, "show the mask");
    let aspect = app.aspect();
    if ui.button("frame all (Home)").clicked()
        && let Some(camera) = &mut app.camera
    {
        camera.frame_all(aspect);
    }
}

pub fn document_panel(app: &mut SlayerApp, ui: &mut Ui) {
    egui::Panel::right("document")
        .default_size(240.0)
        .show(ui, |ui| {
            layers_section(app, ui);
            ui.separator();
            history_section(app, ui);
        });
}

fn layers_section(app: &mut SlayerApp, ui: &mut Ui) {
    ui.heading("Layers");
    let layers = app.status.layers.clone();
    for (l, (name, settings)) in layers.iter().enumerate() {
        let l = l as u32;
        ui.horizontal(|ui| {
            let mut changed = *settings;
            // The viewport's visibility mask has 32 bits.
            ui.add_enabled(l < 32, egui::Checkbox::without_text(&mut changed.visible))
                .on_hover_text("visible")
                .on_disabled_hover_text("only the first 32 layers can be hidden");
            ui.checkbox(&mut changed.active, "")
                .on_hover_text("active: brushed by strokes");
            let [r, g, b] = settings.material.diffuse.map(linear_to_srgb);
            let (rect, swatch) =
                ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::click());
            ui.painter().rect_filled(
                rect,
                2.0,
                Color32::from_rgb((r * 255.0) as u8, (g * 255.0) as u8, (b * 255.0) as u8),
            );
            let swatch = swatch.on_hover_text(
                "the layer's material: click to paint with it, right click to set it",
            );
            swatch.context_menu(|ui| {
                if ui.button("set to the brush's material").clicked() {
                    changed.material = app.tools.material;
                    ui.close();
                }
            });
            if swatch.clicked() {
                app.tools.material = settings.material;
                app.tools.material_name = format!("{name}'s");
            }
            match &mut app.rename {
                Some((editing, text)) if *editing == l => {
                    let response = ui.text_edit_singleline(text);
                    if response.lost_focus() {
                        let text = std::mem::take(text);
                        app.rename = None;
                        if ui.input(|i| i.key_pressed(egui::Key::Enter)) && text != *name {
                            app.send(Command::RenameLayer(l, text));
                        }
                    } else {
                        response.request_focus();
                    }
                }
                _ => {
                    let label = ui.selectable_label(false, name);
                    if label.double_clicked() {
                        app.rename = Some((l, name.clone()));
                    }
                    layer_menu(app, &label, l);
                }
            }
            policy_toggle(ui, &mut changed.policy);
            if changed != *settings {
                app.send(Command::SetLayer(l, changed));
                // Shown at once, and the next change builds on it (the engine's status
                // confirms it; a stroke in progress delays that).
                app.status.layers[l as usize].1 = changed;
            }
        });
    }
    app.tools.view.hidden_layers = layers
        .iter()
        .enumerate()
        .filter(|(l, (_, s))| *l < 32 && !s.visible)
        .fold(0, |bits, (l, _)| bits | 1 << l);
    ui.label(
        RichText::new("double-click a name to rename it, right-click it for the layer tools")
            .weak()
            .small(),
    );
}

/// What a drag on the mesh does: stroke the brush, or trace a layer tool.
fn trace_choice(app: &mut SlayerApp, ui: &mut Ui) {
    ui.horizontal(|ui| {
        ui.label("drag:");
        let trace = &mut app.tools.trace;
        ui.selectable_value(trace, None, "brush");
        ui.selectable_value(trace, Some(Trace::Cut), "cut")
            .on_hover_text("cut the active layers open along the drag");
        ui.selectable_value(trace, Some(Trace::Patch), "patch")
            .on_hover_text("draw a closed outline: a new layer in the brush's material fills it");
    });
    // What a patch, or a duplicate from the Layers panel, makes.
    ui.add(egui::Slider::new(&mut app.tools.lift_edges, 1.0..=8.0).text("new layer: lift"))
        .on_hover_text("how far a patch or a duplicate is lifted off its surface, in edge lengths (the layers' collision distance is one)");
    ui.add(
        egui::Slider::new(&mut app.tools.thickness_edges, 0.0..=8.0).text("new layer: thickness"),
    )
    .on_hover_text("0: an open sheet; more: a closed shell this many edge lengths thick");
}

/// The layer tool's trace while it is drawn: the cut's line, or the patch's outline with a
/// dashed segment where the patch will close it.
pub fn trace_outline(app: &SlayerApp, painter: &Painter) {
    let outline = app.trace_outline();
    if outline.len() < 2 {
        return;
    }
    let colour = Color32::from_rgb(255, 225, 90);
    painter.add(egui::Shape::line(outline.to_vec(), Line::new(2.0, colour)));
    if app.tools.trace == Some(Trace::Patch) {
        let ends = [outline[outline.len() - 1], outline[0]];
        painter.extend(egui::Shape::dashed_line(
            &ends,
            Line::new(1.5, colour),
            6.0,
            4.0,
        ));
    }
}

/// The layer tools on a layer's name: duplicate (its masked part, or all of it) in the brush's
/// material, delete.
/// The layer's proximity policy, switched by a click.
fn policy_toggle(ui: &mut Ui, policy: &mut ProximityPolicy) {
    let fuse = *policy == ProximityPolicy::Fuse;
    let (text, hint) = match fuse {
        false => (
            "collide",
            "collide: contact stops motion, this layer never crosses anything (click: fuse)",
        ),
        true => (
            "fuse",
            "fuse: where this layer touches itself it joins, and necks thinner than the join distance split; other layers still collide (click: collide)",
        ),
    };
    if ui
        .selectable_label(fuse, text)
        .on_hover_text(hint)
        .clicked()
    {
        *policy = match fuse {
            false => ProximityPolicy::Fuse,
            true => ProximityPolicy::Collide,
        };
    }
}

fn layer_menu(app: &mut SlayerApp, label: &egui::Response, layer: u32) {
    label.context_menu(|ui| {
        if ui
            .button("duplicate, lifted off it")
            .on_hover_text("copies the masked part (all of it if nothing is masked) into a new layer in the brush's material, lifted and as thick as the Brush panel's new-layer sliders say")
            .clicked()
        {
            app.send(Command::DuplicateLayer(layer, app.new_layer()));
            ui.close();
        }
        if ui.button("delete layer").clicked() {
            app.send(Command::DeleteLayer(layer));
            ui.close();
        }
    });
}

fn history_section(app: &mut SlayerApp, ui: &mut Ui) {
    ui.heading("History");
    ui.horizontal(|ui| {
        if ui.button("undo").clicked() {
            app.send(Command::Undo);
        }
        if ui.button("redo").clicked() {
            app.send(Command::Redo);
        }
    });
    let done = app.status.done;
    let labels = app.status.history.clone();
    egui::ScrollArea::vertical()
        .stick_to_bottom(true)
        .show(ui, |ui| {
            if ui.selectable_label(done == 0, "(opened)").clicked() {
                (0..done).for_each(|_| app.send(Command::Undo));
            }
            for (i, label) in labels.iter().enumerate() {
                let text = if i < done {
                    RichText::new(label)
                } else {
                    RichText::new(label).weak().italics()
                };
                if ui.selectable_label(i + 1 == done, text).clicked() {
                    let target = i + 1;
                    (target..done).for_each(|_| app.send(Command::Undo));
                    (done..target).for_each(|_| app.send(Command::Redo));
                }
            }
        });
}

pub fn overlays(app: &mut SlayerApp, ctx: &egui::Context) {
    if app.help {
        egui::Window::new("Keys")
            .collapsible(false)
            .open(&mut app.help)
            .show(ctx, |ui| {
                egui::Grid::new("keys").striped(true).show(ui, |ui| {
                    for (keys, what) in super::input::KEY_MAP {
                        ui.label(RichText::new(*keys).strong());
                        ui.label(*what);
                        ui.end_row();
                    }
                });
            });
    }
    let mut open = None;
    if let Some(path) = &mut app.open_path {
        let mut keep = true;
        egui::Window::new("Open")
            .collapsible(false)
            .show(ctx, |ui| {
                ui.label("OBJ, PLY, STL, glTF or .slayer file:");
                let response = ui.text_edit_singleline(path);
                response.request_focus();
                ui.horizontal(|ui| {
                    let enter = ui.input(|i| i.key_pressed(egui::Key::Enter));
                    if ui.button("open").clicked() || enter {
                        open = Some(path.clone());
                    }
                    if ui.button("cancel").clicked()
                        || ui.input(|i| i.key_pressed(egui::Key::Escape))
                    {
                        keep = false;
                    }
                });
            });
        if !keep || open.is_some() {
            app.open_path = None;
        }
    }
    if let Some(path) = open {
        app.send(Command::Open(path.into()));
    }
}

/// The brush's rim on the surface under the pointer, and its normal.
pub fn brush_circle(app: &SlayerApp, painter: &Painter, rect: Rect) {
    let (Some(hit), Some(camera)) = (app.hover, &app.camera) else {
        return;
    };
    // A stroke shows its effect, a trace its outline (`trace_outline`).
    if app.pointer.stroking() || !app.trace_outline().is_empty() {
        return;
    }
    let size = glam::Vec2::new(rect.width(), rect.height());
    let normal = hit.normal;
    let u = normal.any_orthonormal_vector();
    let v = normal.cross(u);
    let radius = app.tools.brush.radius;
    let to_screen = |p: Vec3| {
        camera
            .project(p, size)
            .map(|s| egui::pos2(rect.min.x + s.x, rect.min.y + s.y))
    };
    let rim: Option<Vec<egui::Pos2>> = (0..48)
        .map(|k| {
            let angle = k as f32 / 48.0 * std::f32::consts::TAU;
            to_screen(hit.point + radius * (angle.cos() * u + angle.sin() * v))
        })
        .collect();
    let colour = if app.tools.brush.kind == BrushKind::Mask {
        Color32::from_rgb(120, 200, 255)
    } else {
        Color32::from_rgb(255, 160, 60)
    };
    if let Some(rim) = rim {
        painter.add(egui::Shape::closed_line(rim, Line::new(1.5, colour)));
    }
    if let (Some(a), Some(b)) = (
        to_screen(hit.point),
        to_screen(hit.point + 0.5 * radius * normal),
    ) {
        painter.line_segment([a, b], Line::new(1.5, colour));
    }
}

/// What a stroke's bounds cut short, for the status bar: samples that moved their most steps,
/// remeshing that stopped at its bound of new faces (edges left long), a stroke that stopped
/// where it stretched an edge past its bound.
fn stroke_bounds_met(stroke: &crate::pipeline::StrokeReport) -> String {
    let mut said = String::new();
    if stroke.capped_samples > 0 {
        said += &format!(
            "; {} samples cut short (a runaway brush)",
            stroke.capped_samples
        );
    }
    if stroke.remesh.growth_capped > 0 {
        said += "; remeshing stopped at its bound of new faces (edges left long)";
    }
    if let Some(stretched) = stroke.stopped_stretched {
        said += &format!("; stopped where it stretched an edge to {stretched:.0} L");
    }
    said
}

#[cfg(test)]
mod tests {
    use super::stroke_bounds_met;
    use crate::pipeline::StrokeReport;

    #[test]
    fn the_status_bar_names_the_bounds_a_stroke_met() {
        let mut stroke = StrokeReport::default();
        assert_eq!(stroke_bounds_met(&stroke), "");
        stroke.capped_samples = 2;
        stroke.remesh.growth_capped = 1;
        stroke.stopped_stretched = Some(40.0);
        let said = stroke_bounds_met(&stroke);
        assert!(said.contains("2 samples cut short"), "{said}");
        assert!(said.contains("bound of new faces"), "{said}");
        assert!(said.contains("stretched an edge to 40 L"), "{said}");
    }
}
