//! The app driven as a user would: pointer and key events through egui_kittest, rendered with
//! wgpu (lavapipe in CI), the engine on its own thread as in a window.

use std::time::{Duration, Instant};

use eframe::egui::{self, Event, Key, Modifiers, PointerButton, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::{Harness, SnapshotOptions};
use glam::Vec3;
use slayer::app::{AppSetup, SlayerApp};
use slayer::pipeline::{Pipeline, PipelineSettings};
use slayer::scene::{SceneKind, SceneSpec, generate};
use slayer::session::Session;

const SIZE: [f32; 2] = [1100.0, 700.0];

/// The unit-diameter sphere at about 5K faces.
fn sphere() -> slayer::mesh::Mesh {
    generate(&SceneSpec {
        triangles: 5_000,
        ..SceneSpec::new(SceneKind::Sphere)
    })
    .unwrap()
}

fn plaster() -> Session {
    Session::new(
        generate(&SceneSpec {
            triangles: 6_000,
            ..SceneSpec::new(SceneKind::Plaster)
        })
        .unwrap(),
    )
}

/// Where the test app's Ctrl-S (and "Save and quit") writes.
fn save_path() -> std::path::PathBuf {
    std::env::temp_dir().join(format!("slayer-gui-test-{}.slayer", std::process::id()))
}

fn app(session: Session) -> Harness<'static, SlayerApp> {
    let save_path = save_path();
    let mut harness = Harness::builder()
        .with_size(SIZE)
        .wgpu()
        .build_eframe(move |cc| {
            SlayerApp::new(
                cc,
                AppSetup {
                    session,
                    pipeline: Pipeline::new(PipelineSettings::default()),
                    save_path,
                    replay: Vec::new(),
                    plan: Default::default(),
                    antialias: true,
                },
            )
        });
    settle(&mut harness, "the mesh arrives", |app| {
        app.camera().is_some() && app.status.faces > 0 && app.viewport_rect().is_some()
    });
    harness
}

/// Steps frames until `done` holds (the engine answers on its own thread).
fn settle(harness: &mut Harness<'_, SlayerApp>, what: &str, done: impl Fn(&SlayerApp) -> bool) {
    let start = Instant::now();
    while !done(harness.state()) {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "timed out waiting until {what}"
        );
        harness.step();
        std::thread::sleep(Duration::from_millis(2));
    }
    // One more frame draws what arrived.
    harness.step();
}

fn centre(harness: &Harness<'_, SlayerApp>) -> Pos2 {
    harness.state().viewport_rect().unwrap().center()
}

/// Hovers at `from` until the pointer is over the mesh, then drags to `to` in steps, holding
/// `modifiers`, and waits until the stroke is done.
fn drag(harness: &mut Harness<'_, SlayerApp>, from: Pos2, to: Pos2, modifiers: Modifiers) {
    let path: Vec<Pos2> = (0..=12)
        .map(|k| from + (to - from) * (k as f32 / 12.0))
        .collect();
    drag_through(harness, &path, modifiers);
}

/// A drag along `path` with the primary button, waiting until it is recorded in the history.
fn drag_through(harness: &mut Harness<'_, SlayerApp>, path: &[Pos2], modifiers: Modifiers) {
    let strokes_before = harness.state().status.history.len();
    press_along(harness, path, modifiers);
    release(harness, path[path.len() - 1], modifiers, strokes_before);
}

fn primary(pos: Pos2, pressed: bool, modifiers: Modifiers) -> Event {
    Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers,
    }
}

/// Hovers at the path's start until the pointer is over the mesh, presses there and moves
/// along the rest of the path, one frame a point, the button held.
fn press_along(harness: &mut Harness<'_, SlayerApp>, path: &[Pos2], modifiers: Modifiers) {
    harness.hover_at(path[0]);
    settle(harness, "the pointer is over the mesh", |app| {
        app.hover().is_some()
    });
    harness.event(primary(path[0], true, modifiers));
    harness.step();
    for &p in &path[1..] {
        harness.hover_at(p);
        harness.step();
    }
}

/// Releases the button at `to` and waits until the history has grown past `strokes_before`
/// entries; no message may have come.
fn release(
    harness: &mut Harness<'_, SlayerApp>,
    to: Pos2,
    modifiers: Modifiers,
    strokes_before: usize,
) {
    harness.event(primary(to, false, modifiers));
    settle(harness, "the stroke is recorded or refused", |app| {
        app.idle() && app.status.history.len() > strokes_before || app.messages().count() > 0
    });
    let messages: Vec<&str> = harness.state().messages().collect();
    assert!(messages.is_empty(), "{messages:?}");
}

/// A plain drag between two points given relative to the viewport's centre.
fn drag_across(harness: &mut Harness<'_, SlayerApp>, from: egui::Vec2, to: egui::Vec2) {
    let c = centre(harness);
    drag(harness, c + from, c + to, Modifiers::NONE);
}

fn positions(harness: &Harness<'_, SlayerApp>) -> (Vec<Vec3>, Vec<bool>) {
    harness
        .state()
        .query(|session| {
            let mesh = session.mesh();
            let dead = (0..mesh.vertex_count() as u32)
                .map(|v| mesh.is_vertex_dead(v))
                .collect();
            (mesh.positions().to_vec(), dead)
        })
        .unwrap()
}

fn digest(harness: &Harness<'_, SlayerApp>) -> String {
    harness.state().query(|s| s.mesh().digest()).unwrap()
}

/// The surface points under the drag's ends, picked on the mesh as it was.
fn picked(harness: &Harness<'_, SlayerApp>, pixels: [Pos2; 2]) -> [Vec3; 2] {
    let app = harness.state();
    let rect = app.viewport_rect().unwrap();
    let camera = *app.camera().unwrap();
    let size = glam::Vec2::new(rect.width(), rect.height());
    pixels.map(|p| {
        let ray = camera.ray(glam::Vec2::new(p.x - rect.min.x, p.y - rect.min.y), size);
        app.query(move |s| {
            let mesh = s.mesh();
            slayer::app::Picker::build(mesh, &vec![true; mesh.layer_count()])
                .pick(mesh, &ray)
                .map(|h| h.point)
        })
        .flatten()
        .expect("the drag's ends are on the mesh")
    })
}

fn distance_to_segment(p: Vec3, [a, b]: [Vec3; 2]) -> f32 {
    let t = ((p - a).dot(b - a) / (b - a).length_squared().max(1e-12)).clamp(0.0, 1.0);
    (p - (a + t * (b - a))).length()
}

#[test]
fn a_drag_sculpts_under_the_pointer_only_and_ctrl_z_restores_the_mesh_bit_for_bit() {
    let mut harness = app(plaster());
    let before = digest(&harness);
    let (old, _) = positions(&harness);
    let c = centre(&harness);
    let ends = [c - egui::vec2(80.0, 0.0), c + egui::vec2(80.0, 0.0)];
    let path = picked(&harness, ends);
    let radius = harness.state().tools.brush.radius;

    drag(&mut harness, ends[0], ends[1], Modifiers::NONE);
    assert_ne!(digest(&harness), before, "the stroke changed nothing");
    let (new, dead) = positions(&harness);
    let mut moved_near = 0;
    for v in 0..old.len() {
        if dead[v] || new[v] == old[v] {
            continue;
        }
        let away = distance_to_segment(old[v], path);
        // Remeshing relaxes the ring just outside the brush: two radii bound everything.
        assert!(
            away < 2.0 * radius,
            "vertex {v} moved {} though it is {away} from the stroke (radius {radius})",
            (new[v] - old[v]).length()
        );
        moved_near += (away < radius) as usize;
    }
    assert!(
        moved_near > 50,
        "only {moved_near} vertices under the brush moved"
    );

    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness, "the undo is done", |app| app.status.done == 0);
    assert_eq!(
        digest(&harness),
        before,
        "undo did not restore the mesh bit for bit"
    );
    harness.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    settle(&mut harness, "the redo is done", |app| app.status.done == 1);
    assert_ne!(digest(&harness), before);
}

/// Mean displacement along +z of the vertices within half a radius of the drag.
fn lift(harness: &mut Harness<'_, SlayerApp>, modifiers: Modifiers, dy: f32) -> f32 {
    let (old, _) = positions(harness);
    let c = centre(harness) + egui::vec2(0.0, dy);
    let ends = [c - egui::vec2(40.0, 0.0), c + egui::vec2(40.0, 0.0)];
    let path = picked(harness, ends);
    let radius = harness.state().tools.brush.radius;
    drag(harness, ends[0], ends[1], modifiers);
    let (new, dead) = positions(harness);
    let near: Vec<usize> = (0..old.len())
        .filter(|&v| !dead[v] && distance_to_segment(old[v], path) < 0.5 * radius)
        .collect();
    assert!(!near.is_empty());
    near.iter().map(|&v| new[v].z - old[v].z).sum::<f32>() / near.len() as f32
}

#[test]
fn ctrl_drag_pushes_the_other_way_and_f_sets_the_radius() {
    let mut harness = app(plaster());
    harness.state_mut().tools.brush.strength = 1.0;
    let up = lift(&mut harness, Modifiers::NONE, -120.0);
    let down = lift(&mut harness, Modifiers::COMMAND, 120.0);
    assert!(up > 0.0, "a draw stroke lifts the surface (mean {up})");
    assert!(down < 0.0, "a Ctrl-draw stroke pushes it in (mean {down})");

    let radius = harness.state().tools.brush.radius;
    let c = centre(&harness);
    harness.hover_at(c);
    harness.step();
    harness.key_press(Key::F);
    harness.step();
    harness.hover_at(c + egui::vec2(120.0, 0.0));
    harness.step();
    harness.event(Event::PointerButton {
        pos: c + egui::vec2(120.0, 0.0),
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    harness.step();
    let grown = harness.state().tools.brush.radius;
    assert!(
        grown > 1.5 * radius,
        "F then a move right: radius {radius} -> {grown}"
    );
    // The F-drag was not a stroke.
    assert_eq!(harness.state().status.history.len(), 2);
}

/// Orange pixels (the top layer's false colour, PALETTE[2]) inside the viewport.
fn orange_pixels(harness: &mut Harness<'_, SlayerApp>) -> usize {
    let rect = harness.state().viewport_rect().unwrap();
    let image = harness.render().unwrap();
    image
        .enumerate_pixels()
        .filter(|(x, y, _)| rect.contains(egui::pos2(*x as f32, *y as f32)))
        .filter(|(_, _, p)| {
            let [r, g, b, _] = p.0.map(f32::from);
            r > 60.0 && r > 1.3 * g && g > 1.5 * b
        })
        .count()
}

#[test]
fn hiding_a_layer_removes_it_from_the_picture() {
    let mut harness = app(plaster());
    harness.state_mut().tools.view.false_colour = true;
    harness.step();
    let top = harness.state().status.layers.len() as u32 - 1;
    assert_eq!(
        top, 2,
        "the plaster's flakes are drawn in PALETTE[2], orange"
    );
    let shown = orange_pixels(&mut harness);
    harness.state().set_layer_visible(top, false);
    settle(&mut harness, "the layer is hidden", |app| {
        !app.status.layers[top as usize].1.visible
    });
    let hidden = orange_pixels(&mut harness);
    assert!(shown > 2_000, "the top layer covers only {shown} pixels");
    assert!(
        hidden * 50 < shown,
        "{hidden} orange pixels remain of {shown}"
    );
}

/// The default look and a sculpted one, against images stored in `tests/snapshots/`
/// (`UPDATE_SNAPSHOTS=1 cargo test --release --test gui` rewrites them). Lavapipe renders the
/// same bits on every run; the tolerance (0.5 % of the pixels, each by the default threshold)
/// absorbs a different Mesa version's rounding, not a missing layer or a changed material.
#[test]
fn the_default_and_a_sculpted_plaster_look_as_stored() {
    let mut harness = app(plaster());
    harness.state_mut().tools.phase_times = false;
    harness.step();
    let pixels = (SIZE[0] * SIZE[1]) as usize;
    let options = SnapshotOptions::new().max_failed_pixels(pixels / 200);
    harness.snapshot_options("gui_plaster", &options);
    drag_across(
        &mut harness,
        egui::vec2(-100.0, -30.0),
        egui::vec2(60.0, 40.0),
    );
    harness.snapshot_options("gui_plaster_sculpted", &options);
}

/// Runs `command` (words split at spaces) in `dir`, `slayer` standing for our binary; fails
/// the test with its stderr when it fails.
fn run_in(dir: &std::path::Path, command: &str) {
    let words: Vec<&str> = command
        .split(' ')
        .map(|w| {
            if w == "slayer" {
                env!("CARGO_BIN_EXE_slayer")
            } else {
                w
            }
        })
        .collect();
    let out = std::process::Command::new(words[0])
        .args(&words[1..])
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("{command}: {e}"));
    assert!(
        out.status.success(),
        "{command} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A real window under Xvfb (installed by `tools/test.sh`): the replay drives the pointer's
/// path, the screenshot is the window's own pixels, and the saved session is the mesh
/// `slayer sculpt` makes of the same strokes on the same backend, bit for bit; on the GPU
/// backend the window draws with the engine's device, every stroking frame's positions and
/// normals straight from the backend's buffers.
#[test]
fn a_window_under_xvfb_replays_a_stroke_file_like_sculpt() {
    let xvfb = std::process::Command::new("xvfb-run")
        .arg("--help")
        .output();
    assert!(
        xvfb.is_ok(),
        "xvfb-run is missing: tools/test.sh installs it (apt-get install xvfb xauth)"
    );
    let dir = std::env::temp_dir().join(format!("slayer-gui-xvfb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    run_in(&dir, "slayer scene plaster --triangles 4000 -o p.ply");
    run_in(
        &dir,
        "slayer strokes --scene plaster --triangles 4000 --count 3 -o s.json",
    );
    // The virtual screen is larger than the window, which keeps the size it asked for.
    for backend in ["cpu", "gpu"] {
        let window = std::process::Command::new("xvfb-run")
            .args([
                "-a",
                "-s",
                "-screen 0 1280x1024x24",
                env!("CARGO_BIN_EXE_slayer"),
            ])
            .args([
                "gui",
                "p.ply",
                "--replay",
                "s.json",
                "--exit-after-frames",
                "3",
            ])
            .args(["--save", &format!("gui-{backend}.slayer")])
            .args(["--screenshot", &format!("shot-{backend}.png")])
            .args(["--metrics", &format!("metrics-{backend}.json")])
            .args(["--window", "900x600", "--backend", backend])
            // On lavapipe the window would otherwise open its own device.
            .args(["--device", "shared"])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            window.status.success(),
            "slayer gui --backend {backend} failed: {}",
            String::from_utf8_lossy(&window.stderr)
        );
        run_in(
            &dir,
            &format!(
                "slayer sculpt --input p.ply --strokes s.json --output cli-{backend}.slayer --backend {backend}"
            ),
        );
        let digest = |name: &str| {
            slayer::session::open(&dir.join(name))
                .unwrap()
                .mesh()
                .digest()
        };
        assert_eq!(
            digest(&format!("gui-{backend}.slayer")),
            digest(&format!("cli-{backend}.slayer")),
            "{backend}"
        );
        let shot = image::open(dir.join(format!("shot-{backend}.png")))
            .unwrap()
            .to_rgba8();
        assert_eq!(
            shot.dimensions(),
            (900, 600),
            "the screenshot is the window"
        );
        let metrics = std::fs::read_to_string(dir.join(format!("metrics-{backend}.json"))).unwrap();
        let metrics: serde_json::Value = serde_json::from_str(&metrics).unwrap();
        let figure = |name: &str| metrics[name].as_f64().unwrap();
        let frames = figure("frames_stroking");
        let from_engine = figure("stroking_frames_drawn_from_engine_buffers");
        let expected = if backend == "gpu" { frames } else { 0.0 };
        assert!(
            frames > 0.0 && from_engine == expected,
            "{backend}: {metrics}"
        );
        let mut colours: Vec<[u8; 4]> = shot.pixels().map(|p| p.0).collect();
        colours.sort_unstable();
        colours.dedup();
        assert!(
            colours.len() > 1_000,
            "the screenshot is blank ({} colours)",
            colours.len()
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_paint_brush_lays_down_the_panels_material_through_its_stencil() {
    let mut harness = app(plaster());
    let rust = slayer::material::preset("rust").unwrap().brdf;
    let metal = slayer::material::preset("bare-metal").unwrap().brdf;
    {
        let tools = &mut harness.state_mut().tools;
        tools.brush.kind = slayer::brush::BrushKind::Paint;
        tools.brush.strength = 1.0;
        tools.material = rust;
        tools.stencil = Some(slayer::app::StencilChoice {
            pattern: slayer::brush::Pattern::Checker,
            second: "bare-metal",
            tile: 0.05,
        });
    }
    let before = digest(&harness);
    let (old, _) = positions(&harness);
    drag_across(&mut harness, egui::vec2(-60.0, 0.0), egui::vec2(60.0, 0.0));
    assert_ne!(digest(&harness), before);
    let (new, _) = positions(&harness);
    assert_eq!(old, new, "painting moves nothing");
    let (near_rust, near_metal) = harness
        .state()
        .query(move |s| {
            let close = |a: [f32; 3], b: [f32; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 0.02);
            let brdfs = s.mesh().brdfs();
            let rusty = brdfs
                .iter()
                .filter(|b| close(b.diffuse, rust.diffuse))
                .count();
            let metallic = brdfs
                .iter()
                .filter(|b| close(b.diffuse, metal.diffuse))
                .count();
            (rusty, metallic)
        })
        .unwrap();
    assert!(
        near_rust > 20 && near_metal > 20,
        "rust {near_rust}, bare metal {near_metal}"
    );
}

/// Asks the window to close, as its close button does.
fn request_close(harness: &mut Harness<'_, SlayerApp>) {
    let root = harness
        .input_mut()
        .viewports
        .entry(egui::ViewportId::ROOT)
        .or_default();
    root.events.push(egui::ViewportEvent::Close);
    harness.step();
    // The question's window is laid out, then its widgets are in the tree.
    harness.step();
}

#[test]
fn closing_with_unsaved_changes_asks_and_save_and_quit_saves() {
    use egui_kittest::kittest::Queryable;
    let mut harness = app(plaster());
    request_close(&mut harness);
    assert!(!harness.state().asking_to_save(), "nothing to save yet");

    drag_across(&mut harness, egui::vec2(-50.0, 0.0), egui::vec2(50.0, 0.0));
    assert!(!harness.state().may_close());
    request_close(&mut harness);
    assert!(harness.state().asking_to_save());
    harness.get_by_label("Cancel").click();
    harness.step();
    assert!(!harness.state().asking_to_save() && !harness.state().may_close());

    request_close(&mut harness);
    harness.get_by_label("Save and quit").click();
    settle(&mut harness, "the session is saved", |app| app.may_close());
    let saved = save_path();
    let session = slayer::session::open(&saved).expect("the session was written");
    assert_eq!(session.mesh().digest(), digest(&harness));
    assert_eq!(session.history().entries().len(), 1, "with its history");
    std::fs::remove_file(saved).ok();
}

/// Right-clicks the widget labelled `label` and lets its menu open.
fn open_menu(harness: &mut Harness<'_, SlayerApp>, label: &str) {
    harness.get_by_label(label).click_secondary();
    for _ in 0..3 {
        harness.step();
    }
}

/// The layer tools from the layer's menu: right-click a name, duplicate, then delete the copy;
/// undo takes both back, bit for bit.
#[test]
fn a_layer_is_duplicated_and_deleted_from_its_menu() {
    let mut harness = app(plaster());
    let start = digest(&harness);
    open_menu(&mut harness, "paint");
    harness.get_by_label("duplicate, lifted off it").click();
    settle(&mut harness, "the copy is a layer", |app| {
        app.status.layers.len() == 4
    });
    assert_eq!(harness.state().status.layers[3].0, "paint copy");
    let with_copy = digest(&harness);
    assert_ne!(with_copy, start);
    open_menu(&mut harness, "paint copy");
    harness.get_by_label("delete layer").click();
    settle(&mut harness, "the copy is gone", |app| {
        app.status.layers.len() == 3
    });
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness, "the delete is undone", |app| {
        app.status.layers.len() == 4
    });
    assert_eq!(digest(&harness), with_copy);
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness, "the copy is undone", |app| {
        app.status.layers.len() == 3
    });
    assert_eq!(digest(&harness), start);
}

/// The cut and the patch traced with the pointer: a drag across the sphere cuts it, a closed
/// drag makes a patch layer; each is one undo step.
#[test]
fn cut_and_patch_are_traced_on_the_surface() {
    let mut harness = app(Session::new(sphere()));
    let start = digest(&harness);
    harness.get_by_label("cut").click();
    harness.step();
    assert_eq!(harness.state().tools.trace, Some(slayer::app::Trace::Cut));
    drag_across(
        &mut harness,
        egui::vec2(-120.0, -10.0),
        egui::vec2(120.0, 15.0),
    );
    let checked = |harness: &Harness<'_, SlayerApp>| {
        harness
            .state()
            .query(|s| {
                let mesh = s.mesh();
                let label = s.history().entries().last().map(|e| e.label.clone());
                let sound = mesh.validate().is_ok()
                    && slayer::collide::find_intersections(mesh).total() == 0;
                (label, sound, mesh.layer_count())
            })
            .unwrap()
    };
    assert_eq!(checked(&harness), (Some("cut".to_string()), true, 1));
    harness.get_by_label("patch").click();
    harness.step();
    let outline = ring(centre(&harness), egui::vec2(0.0, 90.0), 55.0, 24);
    drag_through(&mut harness, &outline, Modifiers::NONE);
    assert_eq!(
        checked(&harness),
        (Some("patch layer".to_string()), true, 2)
    );
    for _ in 0..2 {
        harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
        harness.step();
    }
    settle(&mut harness, "both are undone", |app| {
        app.status.layers.len() == 1 && app.idle()
    });
    assert_eq!(digest(&harness), start);
}

/// A ring of `count` + 1 screen points around `c` + `offset` (the first repeated at the end).
fn ring(c: Pos2, offset: egui::Vec2, radius: f32, count: usize) -> Vec<Pos2> {
    (0..=count)
        .map(|k| {
            let a = k as f32 / count as f32 * std::f32::consts::TAU;
            c + offset + egui::vec2(radius * a.cos(), radius * a.sin())
        })
        .collect()
}

/// A trace is drawn while it is dragged (every pointer point of it), dropped by Esc without a
/// change, and gone once released; the patch it makes is lifted and as thick as the Brush
/// panel's new-layer sliders say (on the unit-diameter sphere: the shell's faces between the
/// lift and the lift plus the thickness off the surface, where the default would be an open
/// sheet two edges off). The mid-drag picture is left in the temp folder.
#[test]
fn a_trace_is_drawn_while_dragged_and_the_patch_follows_the_new_layer_sliders() {
    let sphere = sphere();
    let edge = sphere.mean_edge_length();
    let mut harness = app(Session::new(sphere));
    let start = digest(&harness);
    harness.get_by_label("patch").click();
    harness.step();
    let path = ring(centre(&harness), egui::vec2(0.0, 90.0), 55.0, 24);

    // Dropped: Esc mid-drag, then the release changes nothing.
    press_along(&mut harness, &path[..10], Modifiers::NONE);
    assert_eq!(harness.state().trace_outline(), &path[..10]);
    harness.key_press(Key::Escape);
    harness.step();
    assert!(harness.state().trace_outline().is_empty());
    harness.event(primary(path[9], false, Modifiers::NONE));
    settle(&mut harness, "the engine is idle", |app| app.idle());
    assert_eq!(digest(&harness), start);
    assert_eq!(harness.state().status.history.len(), 0);

    {
        let tools = &mut harness.state_mut().tools;
        tools.lift_edges = 3.0;
        tools.thickness_edges = 2.0;
    }
    press_along(&mut harness, &path, Modifiers::NONE);
    assert_eq!(harness.state().trace_outline(), &path[..]);
    let picture = harness.render().unwrap();
    let shot = std::env::temp_dir().join(format!("slayer-gui-trace-{}.png", std::process::id()));
    picture.save(&shot).unwrap();
    release(&mut harness, path[path.len() - 1], Modifiers::NONE, 0);
    assert!(harness.state().trace_outline().is_empty());
    let (open_loops, lowest, highest) = harness
        .state()
        .query(|s| {
            let mesh = s.mesh();
            let open_loops: usize = mesh
                .component_shapes()
                .iter()
                .filter(|c| c.layer == 1)
                .map(|c| c.boundary_loops)
                .sum();
            let (lo, hi) = (0..mesh.vertex_count() as u32)
                .filter(|&v| mesh.is_vertex_live(v) && mesh.vertex_layers()[v as usize] == 1)
                .map(|v| mesh.positions()[v as usize].length() - 0.5)
                .fold((f32::MAX, f32::MIN), |(lo, hi), h| (lo.min(h), hi.max(h)));
            (open_loops, lo, hi)
        })
        .unwrap();
    eprintln!(
        "patch: {open_loops} boundary loops, {:.2}-{:.2} edges off the sphere",
        lowest / edge,
        highest / edge
    );
    assert_eq!(open_loops, 0, "a thick patch is a closed shell");
    assert!(
        lowest > 2.5 * edge,
        "lifted 3 edges: lowest {:.2} L",
        lowest / edge
    );
    assert!(
        highest > 4.5 * edge,
        "3 + 2 edges: highest {:.2} L",
        highest / edge
    );
}

/// The Layers panel's policy switch: a click makes one layer fuse, as an undoable entry.
#[test]
fn a_layer_is_switched_to_fuse_and_back_from_the_layers_panel() {
    use slayer::topology::ProximityPolicy;
    let mut harness = app(plaster());
    let policy =
        |harness: &Harness<'_, SlayerApp>, l: usize| harness.state().status.layers[l].1.policy;
    harness
        .get_all_by_label("collide")
        .next()
        .expect("a collide switch")
        .click();
    settle(&mut harness, "the plaster fuses", |app| {
        app.status.layers[0].1.policy == ProximityPolicy::Fuse
    });
    assert_eq!(policy(&harness, 1), ProximityPolicy::Collide);
    harness.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    settle(&mut harness, "the switch is undone", |app| {
        app.status.layers[0].1.policy == ProximityPolicy::Collide
    });
}
