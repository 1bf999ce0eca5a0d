//! The multi-layer mesh over meshes grouped by kind: closed, open, several components, tiny,
//! high valence; each construction error names its element.

use glam::Vec3;
use slayer::mesh::{INVALID, Mesh, MeshError, MeshVersion, VertexFlags};
use slayer::scene::shapes;

fn kinds() -> Vec<(&'static str, Mesh)> {
    vec![
        ("triangle", shapes::triangle()),
        ("tetrahedron", shapes::tetrahedron()),
        ("octahedron", shapes::octahedron()),
        ("fan of 3", shapes::fan(3)),
        ("fan of 24 (high valence)", shapes::fan(24)),
        ("two patches", shapes::two_patches()),
        (
            "three stacked sheets",
            shapes::stacked_sheets(3, 6, 5, 1.0, 3.0),
        ),
        (
            "geodesic sphere",
            slayer::scene::geodesic_sphere(6, 1.0).unwrap(),
        ),
    ]
}

fn euler_characteristic(mesh: &Mesh) -> i64 {
    mesh.live_vertex_count() as i64 - mesh.edges().len() as i64 + mesh.live_face_count() as i64
}

#[test]
fn every_kind_validates_and_has_consistent_adjacency() {
    for (name, mesh) in kinds() {
        mesh.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut edge_neighbours = vec![Vec::new(); mesh.vertex_count()];
        for [a, b] in mesh.edges() {
            edge_neighbours[a as usize].push(b);
            edge_neighbours[b as usize].push(a);
        }
        let csr = mesh.vertex_faces();
        for v in 0..mesh.vertex_count() as u32 {
            let mut from_fan: Vec<u32> = mesh.faces_around(v).collect();
            from_fan.sort_unstable();
            assert_eq!(from_fan, csr.of(v), "{name}: vertex {v} fan vs CSR");
            let ring = mesh.neighbours(v);
            let expected_ring = if mesh.is_boundary_vertex(v) {
                from_fan.len() + 1
            } else {
                from_fan.len()
            };
            assert_eq!(ring.len(), expected_ring, "{name}: one-ring of {v}");
        }
    }
}

#[test]
fn euler_characteristic_and_components_by_kind() {
    let expect = [
        ("triangle", 1, 1),
        ("tetrahedron", 2, 1),
        ("octahedron", 2, 1),
        ("fan of 3", 1, 1),
        ("fan of 24 (high valence)", 1, 1),
        ("two patches", 2, 2),
        ("three stacked sheets", 3, 3),
        ("geodesic sphere", 2, 1),
    ];
    for ((name, mesh), (expected_name, chi, components)) in kinds().into_iter().zip(expect) {
        assert_eq!(name, expected_name);
        assert_eq!(euler_characteristic(&mesh), chi, "{name}");
        assert_eq!(mesh.components().count(), components, "{name}");
    }
}

#[test]
fn stacked_sheets_label_layers_and_components() {
    let mesh = shapes::stacked_sheets(3, 4, 4, 1.0, 2.0);
    assert_eq!(mesh.layer_count(), 3);
    assert_eq!(mesh.faces_per_layer(), vec![32, 32, 32]);
    let components = mesh.components();
    assert_eq!(components.per_layer(3), vec![1, 1, 1]);
    for (v, &layer) in mesh.vertex_layers().iter().enumerate() {
        assert_eq!(mesh.positions()[v].z, layer as f32 * 2.0);
    }
}

#[test]
fn mean_edge_length_and_normals() {
    let fan = shapes::fan(6);
    // A regular hexagon fan: all 12 edges have length 1.
    assert!((fan.mean_edge_length() - 1.0).abs() < 1e-6);
    assert!(fan.edge_length_stats().coefficient_of_variation() < 1e-6);
    for n in fan.normals() {
        assert!((n.z - 1.0).abs() < 1e-6);
    }
    let sphere = slayer::scene::geodesic_sphere(8, 2.0).unwrap();
    for (p, n) in sphere.positions().iter().zip(sphere.normals()) {
        assert!(p.normalize().dot(*n) > 0.99, "sphere normals point outward");
    }
    assert_eq!(
        Mesh::new(vec![], vec![], vec![], vec![])
            .unwrap()
            .mean_edge_length(),
        0.0
    );
}

/// Refreshing the normals around moved vertices lists their unmoved neighbours, ascending,
/// and leaves every normal as recomputing the moved vertices and their rings does: on each
/// kind of mesh, with every third vertex moved.
#[test]
fn normals_around_moved_vertices_match_a_recompute_of_their_rings() {
    for (name, mut mesh) in kinds() {
        let moved: Vec<u32> = (0..mesh.vertex_count() as u32)
            .filter(|v| v % 3 == 0 && mesh.adjacency().vertex_corner[*v as usize] != INVALID)
            .collect();
        for (k, &v) in moved.iter().enumerate() {
            mesh.positions_mut()[v as usize] += Vec3::new(0.01, -0.02, 0.03) * (k % 4) as f32;
        }
        let mut expected = mesh.clone();
        let mut rim: Vec<u32> = moved.iter().flat_map(|&v| mesh.neighbours(v)).collect();
        rim.retain(|w| !moved.contains(w));
        rim.sort_unstable();
        rim.dedup();
        let mut all: Vec<u32> = moved.iter().chain(&rim).copied().collect();
        all.sort_unstable();
        expected.recompute_normals_at(&all);
        let listed = mesh.recompute_normals_around(&moved, |w| moved.contains(&w));
        assert_eq!(listed, rim, "{name}: the rim");
        assert_eq!(mesh.normals(), expected.normals(), "{name}: the normals");
    }
}

/// Each kind of change gives its part of the version a new stamp and leaves the others;
/// another mesh never shows the same version (a pipeline or GPU copy keyed by it cannot take
/// one mesh for another).
#[test]
fn versions_stamp_changes() {
    let mut mesh = shapes::fan(5);
    assert_ne!(
        mesh.version(),
        shapes::fan(5).version(),
        "two meshes, two versions"
    );
    let before = mesh.version();
    mesh.positions_mut()[0].z = 0.5;
    mesh.recompute_normals_at(&[0, 1, 2]);
    let moved = mesh.version();
    assert!(moved.positions > before.positions);
    let positions = before.positions;
    assert_eq!(
        MeshVersion { positions, ..moved },
        before,
        "only the positions"
    );
    mesh.brdfs_mut()[0].roughness = 0.1;
    let painted = mesh.version();
    assert!(painted.attributes > moved.attributes);
    let attributes = moved.attributes;
    assert_eq!(
        MeshVersion {
            attributes,
            ..painted
        },
        moved,
        "only the BRDFs"
    );
    mesh.flags_mut()[0] = VertexFlags::MASKED;
    let masked = mesh.version();
    assert!(masked.flags > painted.flags);
    let flags = painted.flags;
    assert_eq!(MeshVersion { flags, ..masked }, painted, "flags are apart");
    mesh.kill_face(0);
    assert!(mesh.version().topology > masked.topology);
    assert!(mesh.version().total() > before.total());
}

#[test]
fn killing_faces_then_compacting_keeps_the_mesh_valid() {
    let mut mesh = shapes::stacked_sheets(2, 5, 5, 1.0, 3.0);
    let faces_before = mesh.live_face_count();
    // Remove a whole boundary row of the first sheet: 10 faces, a clean cut.
    for f in 0..10 {
        mesh.kill_face(f);
        mesh.validate()
            .unwrap_or_else(|e| panic!("after killing face {f}: {e}"));
    }
    assert_eq!(mesh.live_face_count(), faces_before - 10);
    let dead_vertices = mesh
        .flags()
        .iter()
        .filter(|f| f.contains(VertexFlags::DEAD))
        .count();
    assert_eq!(
        dead_vertices, 6,
        "the bottom row of vertices lost all faces"
    );
    let map = mesh.compact();
    mesh.validate().unwrap();
    assert_eq!(mesh.face_count(), faces_before - 10);
    assert_eq!(map.face_map[0], INVALID);
    assert_eq!(map.face_map[10], 0);
    assert_eq!(mesh.live_vertex_count(), mesh.vertex_count());
    assert_eq!(mesh.components().count(), 2);
}

#[test]
fn killing_faces_that_pinch_a_vertex_is_reported() {
    // A hexagon fan without faces 1 and 4 leaves the centre joining two separate fans.
    let mut mesh = shapes::fan(6);
    mesh.kill_face(1);
    mesh.validate().unwrap();
    mesh.kill_face(4);
    assert_eq!(
        mesh.validate(),
        Err(MeshError::NonManifoldVertex { vertex: 0 })
    );
}

/// Faces copied out of a mesh take their table from it: the table (or the error) must be the
/// one built afresh from the copy's faces, for selections that leave whole fans, cut fans and
/// pinched vertices (two fans of the selection meeting at one vertex).
#[test]
fn faces_copied_out_have_the_table_a_fresh_build_gives() {
    let (mut tables, mut refusals) = (0, 0);
    for (name, mesh) in kinds() {
        let faces = mesh.face_count() as u32;
        let selections: [Vec<u32>; 4] = [
            (0..faces).collect(),
            (0..faces).filter(|f| f % 2 == 0).collect(),
            (0..faces).filter(|f| f % 3 != 1).rev().collect(),
            (0..faces / 2).collect(),
        ];
        for selection in selections.iter().filter(|s| !s.is_empty()) {
            let copied = mesh.extract_faces(selection, "piece");
            let tris: Vec<[u32; 3]> = {
                let mut order = Vec::new();
                let mut new = vec![INVALID; mesh.vertex_count()];
                selection
                    .iter()
                    .map(|&f| {
                        mesh.faces()[f as usize].map(|v| {
                            if new[v as usize] == INVALID {
                                new[v as usize] = order.len() as u32;
                                order.push(v);
                            }
                            new[v as usize]
                        })
                    })
                    .collect()
            };
            let count = tris.iter().flatten().max().map_or(0, |&v| v as usize + 1);
            let built = one_layer(points(count), tris);
            match (&copied, &built) {
                (Ok((piece, _)), Ok(fresh)) => {
                    assert_eq!(piece.adjacency(), fresh.adjacency(), "{name}");
                    piece.validate().unwrap();
                    tables += 1;
                }
                (Err(a), Err(b)) => {
                    assert_eq!(a, b, "{name}");
                    refusals += 1;
                }
                _ => panic!("{name}: copied {copied:?}, built {built:?}"),
            }
        }
    }
    assert!(
        tables > 20 && refusals > 0,
        "{tables} tables, {refusals} refusals"
    );
}

fn one_layer(positions: Vec<Vec3>, faces: Vec<[u32; 3]>) -> Result<Mesh, MeshError> {
    let layers = vec![0; faces.len()];
    Mesh::new(positions, faces, layers, vec!["l".into()])
}

fn points(n: usize) -> Vec<Vec3> {
    (0..n)
        .map(|i| Vec3::new(i as f32, (i * i % 7) as f32, (i % 3) as f32))
        .collect()
}

#[test]
fn construction_errors_name_the_element() {
    // Three faces on one edge.
    let e = one_layer(points(5), vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::NonManifoldEdge {
                a: 0,
                b: 1,
                faces: 3
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("edge (0, 1)"));

    // Two faces walking an edge the same way.
    let e = one_layer(points(4), vec![[0, 1, 2], [0, 1, 3]]).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::InconsistentOrientation {
                face_a: 0,
                face_b: 1,
                ..
            }
        ),
        "{e}"
    );

    // A bow-tie: two triangles meeting at vertex 0 only.
    let e = one_layer(points(5), vec![[0, 1, 2], [0, 3, 4]]).unwrap_err();
    assert_eq!(e, MeshError::NonManifoldVertex { vertex: 0 });

    // Two closed fans at one vertex (two tetrahedra sharing an apex).
    let mut faces = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
    faces.extend([[0, 4, 5], [0, 6, 4], [0, 5, 6], [4, 6, 5]]);
    let e = one_layer(points(7), faces).unwrap_err();
    assert_eq!(e, MeshError::NonManifoldVertex { vertex: 0 });

    let e = one_layer(points(3), vec![[0, 1, 1]]).unwrap_err();
    assert!(
        matches!(e, MeshError::DegenerateFace { face: 0, vertex: 1 }),
        "{e}"
    );

    let e = one_layer(points(3), vec![[0, 1, 7]]).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::IndexOutOfRange {
                face: 0,
                corner: 2,
                vertex: 7,
                ..
            }
        ),
        "{e}"
    );

    let e = one_layer(points(4), vec![[0, 1, 2]]).unwrap_err();
    assert_eq!(e, MeshError::IsolatedVertex { vertex: 3 });

    let e = Mesh::new(
        points(4),
        vec![[0, 1, 2], [2, 1, 3]],
        vec![0, 1],
        vec!["a".into(), "b".into()],
    )
    .unwrap_err();
    assert!(matches!(e, MeshError::LayerMismatch { face: 1, .. }), "{e}");

    let e = Mesh::new(points(3), vec![[0, 1, 2]], vec![4], vec!["a".into()]).unwrap_err();
    assert!(
        matches!(
            e,
            MeshError::LayerOutOfRange {
                face: 0,
                layer: 4,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn validate_reports_non_finite_and_huge_coordinates() {
    let mut mesh = shapes::fan(4);
    mesh.positions_mut()[2] = Vec3::new(f32::NAN, 0.0, 0.0);
    assert!(matches!(
        mesh.validate(),
        Err(MeshError::NonFinitePosition { vertex: 2, .. })
    ));
    mesh.positions_mut()[2] = Vec3::new(3e19, 0.0, 0.0);
    assert!(matches!(
        mesh.validate(),
        Err(MeshError::CoordinateOutOfRange { vertex: 2, .. })
    ));
}

// ---- patches copied out and put back (whole-mesh remeshing's slabs) ----------------------

/// Faces as their corners' positions, each turned to start at its least corner, sorted: the
/// surface whatever its numbering.
fn face_triples(faces: impl Iterator<Item = [Vec3; 3]>) -> Vec<[[u32; 3]; 3]> {
    let mut triples: Vec<[[u32; 3]; 3]> = faces
        .map(|t| {
            let bits = t.map(|p| p.to_array().map(f32::to_bits));
            let first = (0..3).min_by_key(|&k| bits[k]).unwrap();
            [0, 1, 2].map(|k| bits[(first + k) % 3])
        })
        .collect();
    triples.sort_unstable();
    triples
}

fn live_triples(mesh: &Mesh) -> Vec<[[u32; 3]; 3]> {
    face_triples(
        (0..mesh.face_count())
            .filter(|&f| !mesh.is_face_dead(f))
            .map(|f| mesh.face_positions(f)),
    )
}

fn vertices_where(mesh: &Mesh, keep: impl Fn(Vec3) -> bool) -> Vec<u32> {
    (0..mesh.vertex_count() as u32)
        .filter(|&v| mesh.is_vertex_live(v) && keep(mesh.positions()[v as usize]))
        .collect()
}

/// A patch of scattered vertices (their fans meeting at single vertices, which the copy
/// must close over to stay manifold) copies out valid, and put back untouched leaves every
/// kind of mesh as it was.
#[test]
fn a_patch_put_back_untouched_leaves_the_mesh_as_it_was() {
    for (name, mesh) in kinds() {
        let scattered: Vec<u32> = (0..mesh.vertex_count() as u32).step_by(3).collect();
        let patch = mesh.copy_patch(&scattered).unwrap();
        patch
            .mesh
            .validate()
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut back = mesh.clone();
        back.put_back(&[patch]).unwrap();
        back.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(back.faces(), mesh.faces(), "{name}");
        assert_eq!(back.positions(), mesh.positions(), "{name}");
    }
}

/// Splits, flips and collapses made inside a copied cap of a sphere come back as if made in
/// place: a valid sphere (χ 2) whose faces are those outside the patch and the copy's.
#[test]
fn edits_in_a_patch_come_back_as_if_made_in_place() {
    let sphere = slayer::scene::geodesic_sphere(12, 1.0).unwrap();
    let cap = vertices_where(&sphere, |p| p.z > 0.3);
    let mut patch = sphere.copy_patch(&cap).unwrap();
    let copy = &mut patch.mesh;
    let interior = |copy: &Mesh, c: u32| {
        let (a, b) = copy.edge_vertices(c);
        [a, b].iter().all(|&v| copy.positions()[v as usize].z > 0.7)
    };
    let (mut splits, mut flips, mut collapses) = (0, 0, 0);
    for c in (0..3 * copy.face_count() as u32).step_by(7) {
        if !copy.is_face_dead(c as usize / 3) && interior(copy, c) {
            copy.split_edge(c, 0.5);
            splits += 1;
        }
    }
    for c in (0..3 * copy.face_count() as u32).step_by(11) {
        if !copy.is_face_dead(c as usize / 3) && interior(copy, c) && copy.is_flip_ok(c) {
            copy.flip_edge(c);
            flips += 1;
        }
    }
    for c in (0..3 * copy.face_count() as u32).step_by(13) {
        if !copy.is_face_dead(c as usize / 3) && interior(copy, c) && copy.is_collapse_ok(c) {
            let (a, b) = copy.edge_vertices(c);
            let middle = 0.5 * (copy.positions()[a as usize] + copy.positions()[b as usize]);
            copy.collapse_edge(c, middle);
            collapses += 1;
        }
    }
    assert!(
        splits > 20 && flips > 5 && collapses > 5,
        "{splits} {flips} {collapses}"
    );
    copy.validate().unwrap();
    let outside = (0..sphere.face_count())
        .filter(|f| !patch.faces.contains(&(*f as u32)))
        .map(|f| sphere.face_positions(f));
    let expected = face_triples(
        outside.chain(
            (0..copy.face_count())
                .filter(|&f| !copy.is_face_dead(f))
                .map(|f| copy.face_positions(f)),
        ),
    );
    let mut mesh = sphere.clone();
    let maps = mesh.put_back(std::slice::from_ref(&patch)).unwrap();
    mesh.validate().unwrap();
    assert_eq!(euler_characteristic(&mesh), 2);
    assert_eq!(live_triples(&mesh), expected);
    for (i, &v) in maps[0].iter().enumerate() {
        if v != INVALID {
            assert_eq!(mesh.positions()[v as usize], patch.mesh.positions()[i]);
        }
    }
}

/// Work that reached a patch's rim (a rim vertex moved, or its fan rewired inside the copy)
/// cannot be put back by the patch alone: refused, and the mesh kept as it was. So are two
/// patches holding one face.
#[test]
fn a_patch_whose_rim_changed_or_that_overlaps_another_is_refused() {
    let sphere = slayer::scene::geodesic_sphere(8, 1.0).unwrap();
    let cap = vertices_where(&sphere, |p| p.z > 0.5);
    let patch = sphere.copy_patch(&cap).unwrap();
    // A vertex of the copy's rim: one whose faces in the mesh are not all copied.
    let rim = (0..patch.sources.len())
        .find(|&i| {
            let v = patch.sources[i];
            sphere.faces_around(v).any(|f| !patch.faces.contains(&f))
        })
        .unwrap();
    let mut moved = patch.clone();
    moved.mesh.positions_mut()[rim] += Vec3::splat(0.01);
    let mut mesh = sphere.clone();
    assert!(mesh.put_back(&[moved]).is_err());
    assert_eq!(mesh.positions(), sphere.positions());
    assert_eq!(mesh.faces(), sphere.faces());
    // A flip inside the copy, of an edge whose faces border only copied faces but meet a rim
    // vertex: that vertex's fan, which runs on outside the copy, changed.
    let on_rim = |l: u32| {
        let v = patch.sources.get(l as usize).copied();
        v.is_some_and(|v| sphere.faces_around(v).any(|f| !patch.faces.contains(&f)))
    };
    let inner_face = |copy: &Mesh, f: u32| {
        (0..3).all(|k| copy.adjacency().opposite[3 * f as usize + k] != INVALID)
    };
    let mut flipped = patch.clone();
    let copy = &mut flipped.mesh;
    let corner = (0..3 * copy.face_count() as u32)
        .find(|&c| {
            let o = copy.adjacency().opposite[c as usize];
            o != INVALID
                && inner_face(copy, c / 3)
                && inner_face(copy, o / 3)
                && copy.faces()[c as usize / 3].iter().any(|&l| on_rim(l))
                && copy.is_flip_ok(c)
        })
        .unwrap();
    copy.flip_edge(corner);
    assert!(mesh.put_back(&[flipped]).is_err());
    assert_eq!(mesh.faces(), sphere.faces());
    let band = sphere
        .copy_patch(&vertices_where(&sphere, |p| p.z > 0.4))
        .unwrap();
    assert!(mesh.put_back(&[patch, band]).is_err());
    assert_eq!(mesh.faces(), sphere.faces());
    mesh.validate().unwrap();
}
