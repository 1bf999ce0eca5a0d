//! The preview renderer on the adapter the machine has (lavapipe in CI; these tests never skip):
//! the shader against the CPU reference of the BRDF, a small scene against a stored image,
//! chunked draws, and inputs that must give an error or a blank image, never a panic.
//!
//! `SLAYER_BLESS=1 cargo test --release --test render` rewrites the stored reference image.

use std::path::Path;
use std::sync::OnceLock;

use glam::{Vec2, Vec3, Vec4};
use slayer::gpu::{AdapterChoice, GpuContext};
use slayer::material;
use slayer::mesh::{Brdf, Mesh};
use slayer::render::brdf::{Lighting, shade};
use slayer::render::{BACKGROUND, CameraSpec, Image, RenderError, RenderOptions, render};
use slayer::scene::{SceneKind, SceneSpec, generate, shapes};

fn gpu() -> &'static GpuContext {
    static GPU: OnceLock<GpuContext> = OnceLock::new();
    GPU.get_or_init(|| {
        let gpu = GpuContext::new(AdapterChoice {
            allow_software: true,
        })
        .unwrap_or_else(|e| panic!("render tests need an adapter (run tools/test.sh): {e}"));
        eprintln!("render tests on: {}", gpu.adapter);
        gpu
    })
}

fn options(width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        ..RenderOptions::default()
    }
}

fn linear_to_srgb(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn background_pixel() -> [u8; 4] {
    let [r, g, b] = BACKGROUND.map(|c| (linear_to_srgb(c as f32) * 255.0).round() as u8);
    [r, g, b, 255]
}

/// A flat square sheet on z = 0, every vertex in `brdf`.
fn flat_sheet(brdf: Brdf) -> Mesh {
    let (positions, faces) = shapes::grid_patch(8, 8, 0.25, 0.0, Vec2::splat(-1.0));
    let layers = vec![0; faces.len()];
    let mut mesh = Mesh::new(positions, faces, layers, vec!["sheet".into()]).unwrap();
    mesh.set_layer_brdf(0, brdf);
    mesh
}

#[test]
fn the_shader_matches_the_cpu_reference_brdf() {
    // Looking at a flat sheet, every pixel on it is the CPU model's radiance for the point the
    // pixel sees, encoded as sRGB.
    let (width, height) = (48, 40);
    for brdf in [
        material::PLASTER.brdf,
        material::PAINT.brdf,
        material::BARE_METAL.brdf,
        Brdf::new([0.2, 0.5, 0.1], [0.9, 0.9, 0.9], 0.05),
    ] {
        let mesh = flat_sheet(brdf);
        let rendered = render(
            gpu(),
            &mesh,
            &RenderOptions {
                camera: CameraSpec {
                    azimuth: 20.0,
                    elevation: 60.0,
                    distance: 0.8,
                },
                antialias: false,
                ..options(width, height)
            },
        )
        .unwrap();
        let camera = rendered.camera;
        let lighting = Lighting::for_view(camera.right, camera.up, camera.toward);
        let inverse = camera.view_proj.inverse();
        let mut compared = 0;
        let mut worst = 0.0f32;
        for y in 0..height {
            for x in 0..width {
                // The point on z = 0 under the pixel's centre.
                let ndc = Vec2::new(
                    (x as f32 + 0.5) / width as f32 * 2.0 - 1.0,
                    1.0 - (y as f32 + 0.5) / height as f32 * 2.0,
                );
                let unproject = |z: f32| {
                    let p = inverse * Vec4::new(ndc.x, ndc.y, z, 1.0);
                    p.truncate() / p.w
                };
                let (near, far) = (unproject(0.0), unproject(1.0));
                let t = near.z / (near.z - far.z);
                let point = near + (far - near) * t;
                // Stay clear of the sheet's rim, where pixels are partly background.
                if point.x.abs() > 0.9 || point.y.abs() > 0.9 {
                    continue;
                }
                let v = (camera.eye - point).normalize();
                let expected = shade(&brdf, Vec3::Z, v, &lighting).to_array();
                let actual = rendered.image.pixel(x, y);
                for k in 0..3 {
                    let want = linear_to_srgb(expected[k]) * 255.0;
                    worst = worst.max((actual[k] as f32 - want).abs());
                }
                compared += 1;
            }
        }
        assert!(compared > 300, "{compared} pixels on the sheet");
        // Rounding, sRGB encoding in hardware and fast pow (lavapipe: 0.62 levels at most).
        assert!(worst <= 2.0, "{brdf:?}: off by {worst} levels");
    }
}

const REFERENCE: &str = "tests/data/render-plaster-above-64x64.png";

/// The stored image's view: straight down on the square plaster, near enough that it fills the
/// whole frame and every pixel shows a layer.
fn filling_the_frame() -> RenderOptions {
    RenderOptions {
        camera: CameraSpec {
            azimuth: 0.0,
            elevation: 90.0,
            distance: 0.7,
        },
        ..options(64, 64)
    }
}

/// Whether `image` is the stored one up to what rasterizers differ in (coverage and rounding,
/// lavapipe against hardware): a small mean difference and a few pixels along edges.
fn matches_reference(image: &Image, expected: &Image) -> (bool, String) {
    let difference = image.difference(expected, 16).unwrap();
    let ok = difference.mean < 2.0 && difference.pixels_over <= 64 * 64 / 50;
    (ok, format!("{difference:?}"))
}

#[test]
fn a_small_plaster_scene_matches_the_stored_image() {
    let mut mesh = generate(&SceneSpec {
        triangles: 2000,
        ..SceneSpec::new(SceneKind::Plaster)
    })
    .unwrap();
    let rendered = render(gpu(), &mesh, &filling_the_frame()).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(REFERENCE);
    if std::env::var_os("SLAYER_BLESS").is_some() {
        std::fs::write(&path, rendered.image.to_png().unwrap()).unwrap();
        eprintln!("wrote {}", path.display());
    }
    let background = background_pixel();
    let image = &rendered.image;
    let empty = (0..image.height)
        .flat_map(|y| (0..image.width).map(move |x| (x, y)))
        .filter(|&(x, y)| image.pixel(x, y) == background)
        .count();
    assert_eq!(empty, 0, "the mesh fills the frame");
    let expected = Image::read_png(&path).unwrap();
    let (ok, difference) = matches_reference(image, &expected);
    if !ok {
        let actual = std::env::temp_dir().join("render-plaster-above-64x64-actual.png");
        std::fs::write(&actual, rendered.image.to_png().unwrap()).unwrap();
        panic!(
            "{difference} against {REFERENCE}; this render is at {} (SLAYER_BLESS=1 to accept it)",
            actual.display()
        );
    }
    // The tolerance is not so loose that a vanished layer or a changed material passes: the
    // flakes hidden, or painted rust instead of peeling paint, each fail it.
    let flakes_hidden = RenderOptions {
        layers: Some(vec![0, 1]),
        ..filling_the_frame()
    };
    let hidden = render(gpu(), &mesh, &flakes_hidden).unwrap().image;
    let (passes, difference) = matches_reference(&hidden, &expected);
    eprintln!("the flakes hidden: {difference}");
    assert!(!passes, "the flakes hidden still match: {difference}");
    mesh.set_layer_brdf(2, material::RUST.brdf);
    let repainted = render(gpu(), &mesh, &filling_the_frame()).unwrap().image;
    let (passes, difference) = matches_reference(&repainted, &expected);
    eprintln!("the flakes in rust: {difference}");
    assert!(!passes, "the flakes in rust still match: {difference}");
}

#[test]
fn layers_false_colours_and_wireframe_change_the_image() {
    let mesh = generate(&SceneSpec {
        triangles: 2000,
        ..SceneSpec::new(SceneKind::Plaster)
    })
    .unwrap();
    let plain = render(gpu(), &mesh, &options(64, 48)).unwrap();
    assert!(plain.faces > 1500);
    for variant in [
        RenderOptions {
            layers: Some(vec![0]),
            ..options(64, 48)
        },
        RenderOptions {
            false_colour: true,
            ..options(64, 48)
        },
        RenderOptions {
            wireframe: true,
            ..options(64, 48)
        },
    ] {
        let other = render(gpu(), &mesh, &variant).unwrap();
        let difference = other.image.difference(&plain.image, 16).unwrap();
        assert!(difference.pixels_over > 30, "{variant:?}: {difference:?}");
    }
    let base_only = render(
        gpu(),
        &mesh,
        &RenderOptions {
            layers: Some(vec![0]),
            ..options(64, 48)
        },
    )
    .unwrap();
    assert_eq!(base_only.faces, mesh.faces_per_layer()[0]);
}

#[test]
fn large_meshes_split_into_several_draws_with_the_same_image() {
    let mesh = generate(&SceneSpec {
        triangles: 2000,
        ..SceneSpec::new(SceneKind::Plaster)
    })
    .unwrap();
    let whole = render(gpu(), &mesh, &options(80, 60)).unwrap();
    let split = render(
        gpu(),
        &mesh,
        &RenderOptions {
            max_vertices_per_draw: Some(100),
            ..options(80, 60)
        },
    )
    .unwrap();
    assert_eq!(whole.draws, 1);
    assert!(split.draws > 10, "{} draws", split.draws);
    assert_eq!(split.faces, whole.faces);
    let difference = split.image.difference(&whole.image, 0).unwrap();
    assert_eq!(difference.max, 0, "{difference:?}");
}

#[test]
fn empty_and_degenerate_meshes_render_without_panicking() {
    let background = background_pixel();
    let blank = |image: &Image| {
        image
            .rgba
            .chunks_exact(4)
            .all(|p| p.iter().zip(background).all(|(a, b)| a.abs_diff(b) <= 1))
    };
    // No vertices at all.
    let empty = Mesh::new(Vec::new(), Vec::new(), Vec::new(), Vec::new()).unwrap();
    let rendered = render(gpu(), &empty, &options(32, 24)).unwrap();
    assert_eq!(rendered.faces, 0);
    assert!(blank(&rendered.image));
    // A layer with nothing on it.
    let sheets = shapes::stacked_sheets(2, 3, 3, 1.0, 1.0);
    let mut only = options(32, 24);
    only.layers = Some(vec![]);
    let rendered = render(gpu(), &sheets, &only).unwrap();
    assert_eq!(rendered.faces, 0);
    assert!(blank(&rendered.image));
    // Every vertex at one point: faces of no area, a box of no size.
    let mut point = shapes::stacked_sheets(1, 3, 3, 1.0, 0.0);
    for p in point.positions_mut() {
        *p = Vec3::splat(0.5);
    }
    point.recompute_normals();
    render(gpu(), &point, &options(32, 24)).unwrap();
    // Non-finite positions are left out of the drawing and the framing.
    let mut broken = shapes::stacked_sheets(1, 3, 3, 1.0, 0.0);
    broken.positions_mut()[0] = Vec3::NAN;
    broken.positions_mut()[5] = Vec3::INFINITY;
    let rendered = render(gpu(), &broken, &options(32, 24)).unwrap();
    assert!(rendered.faces > 0 && rendered.faces < broken.face_count());
    assert!(!blank(&rendered.image));
    // A sheet seen exactly edge-on covers (almost) nothing.
    let edge_on = RenderOptions {
        camera: CameraSpec {
            azimuth: 0.0,
            elevation: 0.0,
            distance: 1.0,
        },
        ..options(32, 24)
    };
    render(gpu(), &flat_sheet(Brdf::CLAY), &edge_on).unwrap();
}

#[test]
fn bad_sizes_and_layers_are_errors() {
    let mesh = shapes::stacked_sheets(1, 3, 3, 1.0, 0.0);
    for (width, height) in [(0, 10), (10, 0)] {
        let error = render(gpu(), &mesh, &options(width, height)).unwrap_err();
        assert!(matches!(error, RenderError::EmptySize { .. }), "{error}");
    }
    let max = gpu().limits.max_texture_dimension_2d;
    let error = render(gpu(), &mesh, &options(max + 1, 8)).unwrap_err();
    assert!(matches!(error, RenderError::TooLarge { .. }), "{error}");
    assert!(error.to_string().contains(&max.to_string()), "{error}");
    let error = render(gpu(), &mesh, &options(9000, 9000)).unwrap_err();
    assert!(matches!(error, RenderError::TooLarge { .. }), "{error}");
    let mut layers = options(8, 8);
    layers.layers = Some(vec![3]);
    let error = render(gpu(), &mesh, &layers).unwrap_err();
    assert!(
        error.to_string().contains("layer 3 does not exist"),
        "{error}"
    );
}

#[test]
fn painted_brdfs_show_in_the_image() {
    // Half the sheet in rust, half in plaster: the two halves differ in colour, and a vertex
    // blend between them renders in between.
    let mut mesh = flat_sheet(material::PLASTER.brdf);
    let rust = material::RUST.brdf;
    let brdfs: Vec<Brdf> = mesh
        .positions()
        .iter()
        .map(|p| {
            if p.x > 0.0 {
                rust
            } else {
                material::PLASTER.brdf
            }
        })
        .collect();
    mesh.set_brdfs(brdfs).unwrap();
    let top = RenderOptions {
        camera: CameraSpec {
            azimuth: 0.0,
            elevation: 90.0,
            distance: 1.0,
        },
        ..options(64, 64)
    };
    let image = render(gpu(), &mesh, &top).unwrap().image;
    // Looking straight down with +y up in the image: x grows to the right.
    let left = image.pixel(16, 32);
    let right = image.pixel(48, 32);
    assert!(left[2] > right[2] + 60, "plaster {left:?}, rust {right:?}");
    assert!(right[0] > right[2] + 60, "rust is red: {right:?}");
}

#[test]
fn camera_specs_parse_and_reject_nonsense() {
    let spec: CameraSpec = "-30,50".parse().unwrap();
    assert_eq!(
        (spec.azimuth, spec.elevation, spec.distance),
        (-30.0, 50.0, 1.0)
    );
    let spec: CameraSpec = "10, 90, 0.5".parse().unwrap();
    assert_eq!(spec.distance, 0.5);
    for bad in ["", "1", "1,2,3,4", "a,2", "0,91", "0,45,0", "0,45,nan"] {
        assert!(bad.parse::<CameraSpec>().is_err(), "{bad}");
    }
}

/// Each layer of the plaster scene rendered alone covers the frame's middle, and its pixels'
/// colour is nearer its own material's diffuse colour than any other layer's: a layer that
/// vanished, or a material changed or swapped, fails.
#[test]
fn each_layer_shows_in_its_own_colour() {
    let mesh = generate(&SceneSpec {
        triangles: 4000,
        ..SceneSpec::new(SceneKind::Plaster)
    })
    .unwrap();
    let layers = mesh.layer_count();
    // Each layer's mean diffuse albedo, as a direction in colour space.
    let mut diffuse = vec![Vec3::ZERO; layers];
    for (v, brdf) in mesh.brdfs().iter().enumerate() {
        diffuse[mesh.vertex_layers()[v] as usize] += Vec3::from_array(brdf.diffuse);
    }
    let background = background_pixel();
    for layer in 0..layers {
        let alone = RenderOptions {
            layers: Some(vec![layer as u32]),
            ..options(96, 64)
        };
        let image = render(gpu(), &mesh, &alone).unwrap().image;
        let mut covered = Vec3::ZERO;
        let mut count = 0usize;
        for y in 0..image.height {
            for x in 0..image.width {
                let p = image.pixel(x, y);
                if p != background {
                    let srgb = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0;
                    covered += srgb.powf(2.2);
                    count += 1;
                }
            }
        }
        // Seen from above at an angle the whole layers cover 0.28–0.29 of the frame, the patchy
        // top one 0.06: a layer that vanished covers nothing.
        let share = count as f32 / (image.width * image.height) as f32;
        assert!(share > 0.02, "layer {layer} covers {share} of the frame");
        // Cosines to the layers' diffuse colours, own against the next: 0.9998 / 0.977,
        // 0.9998 / 0.943, 0.9967 / 0.9934 (the lights are warm and cool; the top layer's
        // paint is near the base's hue).
        let colour = (covered / count as f32).normalize();
        let nearest = (0..layers)
            .max_by(|&a, &b| {
                let similarity = |k: usize| colour.dot(diffuse[k].normalize());
                similarity(a).total_cmp(&similarity(b))
            })
            .unwrap();
        assert_eq!(
            nearest, layer,
            "layer {layer} looks {colour} nearest layer {nearest}'s diffuse"
        );
    }
}
