//! The session file (`.slayer`): the mesh with every attribute, the layer settings, the brush,
//! and optionally the history, in one versioned binary file (docs/session.md).
//!
//! Layout: 8 magic bytes, the format version (`u32`), the section count (`u32`), then each
//! section as a 4-byte tag, its length (`u64`), the CRC-32 of its bytes (`u32`) and the bytes.
//! Sections: `MESH` (the arrays as in memory, dead rows included, so a history replays on them),
//! `LAYR` (per layer: visible, active, policy, material), `BRSH` (the brush, JSON), `HIST`
//! (optional: the cap, how many entries are done, and each entry's label, rows and layer
//! settings). A reader skips sections it does not know; a wrong magic, a newer version or a
//! checksum that does not match is a one-line error.

use std::path::Path;

use thiserror::Error;

use super::history::Entry;
use super::{BrushSettings, History, LayerSettings, ProximityPolicy, Session};
use crate::codec::{DecodeError, Reader, Writer};
use crate::io::{AtomicBatch, ImportOptions, ImportReport, IoError};
use crate::mesh::{Brdf, Mesh, MeshDelta, RawMeshError};

/// The first bytes of every session file: a high byte and a CR-LF/LF pair catch transfers
/// that mangle binary files, as PNG's do.
const MAGIC: [u8; 8] = *b"\x89SLR\r\n\x1a\n";

/// The format version this build writes and the newest it reads.
pub const VERSION: u32 = 1;

/// Why a session file could not be read; nothing was loaded.
#[derive(Debug, Error)]
pub enum SessionFileError {
    #[error(transparent)]
    Io(#[from] IoError),
    #[error("{path}: not a slayer session file (it does not start with the session magic)")]
    NotASession { path: String },
    #[error(
        "{path}: session format version {found}; this slayer reads up to version {VERSION} (a newer slayer wrote it)"
    )]
    Version { path: String, found: u32 },
    #[error("{path}: section {section} is damaged (its checksum does not match)")]
    Checksum { path: String, section: String },
    #[error("{path}: no {section} section")]
    Missing { path: String, section: &'static str },
    #[error("{path}: {source}")]
    Decode { path: String, source: DecodeError },
    #[error("{path}: {source}")]
    Mesh { path: String, source: RawMeshError },
    #[error("{path}: {problem}")]
    Invalid { path: String, problem: String },
}

/// The bytes of a session file; the history too when `with_history`.
pub fn write_session(session: &Session, with_history: bool) -> Vec<u8> {
    let mut sections: Vec<([u8; 4], Vec<u8>)> = Vec::new();
    let mut mesh = Writer::default();
    session.mesh.write_raw(&mut mesh);
    sections.push((*b"MESH", mesh.bytes));
    let mut layers = Writer::default();
    write_layers(&mut layers, &session.layers);
    sections.push((*b"LAYR", layers.bytes));
    let brush = serde_json::to_vec(&session.brush).expect("brush settings serialize");
    sections.push((*b"BRSH", brush));
    if with_history {
        let mut history = Writer::default();
        write_history(&mut history, &session.history);
        sections.push((*b"HIST", history.bytes));
    }
    let mut out = Writer::default();
    out.bytes.extend_from_slice(&MAGIC);
    out.u32(VERSION);
    out.u32(sections.len() as u32);
    for (tag, bytes) in sections {
        out.bytes.extend_from_slice(&tag);
        out.u64(bytes.len() as u64);
        out.u32(crc32fast::hash(&bytes));
        out.bytes.extend_from_slice(&bytes);
    }
    out.bytes
}

/// Reads a session file's bytes (`path` names it in messages).
pub fn read_session(bytes: &[u8], path: &str) -> Result<Session, SessionFileError> {
    let decode = |source| SessionFileError::Decode {
        path: path.to_string(),
        source,
    };
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        return Err(SessionFileError::NotASession {
            path: path.to_string(),
        });
    }
    let mut input = Reader::new(&bytes[MAGIC.len()..]);
    let found = input.u32("format version").map_err(decode)?;
    if found > VERSION || found == 0 {
        return Err(SessionFileError::Version {
            path: path.to_string(),
            found,
        });
    }
    let count = input.u32("section count").map_err(decode)?;
    let mut sections: Vec<([u8; 4], &[u8])> = Vec::new();
    for _ in 0..count {
        let tag: [u8; 4] = input
            .take(4, "section tag")
            .map_err(decode)?
            .try_into()
            .expect("4");
        let length = input.u64("section length").map_err(decode)?;
        let checksum = input.u32("section checksum").map_err(decode)?;
        let what = format!("section {}", show_tag(&tag));
        let length = usize::try_from(length)
            .map_err(|_| decode(DecodeError::new(&what, "longer than memory")))?;
        let body = input.take(length, &what).map_err(decode)?;
        if crc32fast::hash(body) != checksum {
            return Err(SessionFileError::Checksum {
                path: path.to_string(),
                section: show_tag(&tag),
            });
        }
        sections.push((tag, body));
    }
    let section = |tag: &[u8; 4], name: &'static str| {
        sections
            .iter()
            .find(|(t, _)| t == tag)
            .map(|(_, body)| *body)
            .ok_or(SessionFileError::Missing {
                path: path.to_string(),
                section: name,
            })
    };
    let mesh = Mesh::read_raw(&mut Reader::new(section(b"MESH", "MESH")?)).map_err(|source| {
        SessionFileError::Mesh {
            path: path.to_string(),
            source,
        }
    })?;
    let layers = read_layers(&mut Reader::new(section(b"LAYR", "LAYR")?)).map_err(decode)?;
    let invalid = |problem: String| SessionFileError::Invalid {
        path: path.to_string(),
        problem,
    };
    if layers.len() != mesh.layer_count() {
        return Err(invalid(format!(
            "{} layer settings for {} layers",
            layers.len(),
            mesh.layer_count()
        )));
    }
    let brush: BrushSettings = serde_json::from_slice(section(b"BRSH", "BRSH")?)
        .map_err(|e| invalid(format!("the brush settings are unreadable ({e})")))?;
    let history = match section(b"HIST", "HIST") {
        Ok(body) => {
            let history = read_history(&mut Reader::new(body)).map_err(decode)?;
            check_history(&history, &mesh).map_err(invalid)?;
            history
        }
        Err(_) => History::default(),
    };
    Ok(Session::from_parts(mesh, layers, brush, history))
}

/// A tag as text for messages, its bytes escaped.
fn show_tag(tag: &[u8; 4]) -> String {
    tag.escape_ascii().to_string()
}

fn write_layers(out: &mut Writer, layers: &[LayerSettings]) {
    out.u64(layers.len() as u64);
    for layer in layers {
        out.u32(layer.visible as u32);
        out.u32(layer.active as u32);
        out.u32(match layer.policy {
            ProximityPolicy::Collide => 0,
            ProximityPolicy::Fuse => 1,
        });
        out.array(&layer.material.as_array());
    }
}

fn read_layers(input: &mut Reader) -> Result<Vec<LayerSettings>, DecodeError> {
    let count = input.u64("layer settings")?;
    // Each layer takes at least 12 bytes and its material's 36.
    if count > (input.remaining() / 48) as u64 {
        return Err(DecodeError::new("layer settings", "more layers than bytes"));
    }
    let flag = |input: &mut Reader, what: &str| match input.u32(what)? {
        0 => Ok(false),
        1 => Ok(true),
        other => Err(DecodeError::new(
            what,
            format!("{other} is neither 0 nor 1"),
        )),
    };
    (0..count)
        .map(|_| {
            let visible = flag(input, "layer visible")?;
            let active = flag(input, "layer active")?;
            let policy = match input.u32("layer policy")? {
                0 => ProximityPolicy::Collide,
                1 => ProximityPolicy::Fuse,
                other => {
                    return Err(DecodeError::new("layer policy", format!("unknown {other}")));
                }
            };
            let values: Vec<f32> = input.array("layer material")?;
            let values: [f32; 7] = values
                .try_into()
                .map_err(|_| DecodeError::new("layer material", "not 7 numbers"))?;
            Ok(LayerSettings {
                visible,
                active,
                policy,
                material: Brdf::from_array(values),
            })
        })
        .collect()
}

fn write_history(out: &mut Writer, history: &History) {
    out.u64(history.cap_bytes() as u64);
    out.u64(history.done() as u64);
    out.u64(history.entries().len() as u64);
    for entry in history.entries() {
        out.string(&entry.label);
        entry.mesh.write(out);
        match &entry.layers {
            None => out.u32(0),
            Some((before, after)) => {
                out.u32(1);
                write_layers(out, before);
                write_layers(out, after);
            }
        }
    }
}

fn read_history(input: &mut Reader) -> Result<History, DecodeError> {
    let cap = input.u64("history cap")? as usize;
    let done = input.u64("history position")? as usize;
    let count = input.u64("history entries")? as usize;
    if done > count || count > input.remaining() {
        return Err(DecodeError::new("history", "counts do not agree"));
    }
    let mut entries = Vec::with_capacity(count);
    for _ in 0..count {
        let label = input.string("entry label")?;
        let mesh = MeshDelta::read(input)?;
        let layers = match input.u32("entry layers")? {
            0 => None,
            1 => Some((read_layers(input)?, read_layers(input)?)),
            other => return Err(DecodeError::new("entry layers", format!("marker {other}"))),
        };
        entries.push(Entry {
            label,
            mesh,
            layers,
        });
    }
    Ok(History::restored(entries, done, cap))
}

/// Replays the history on a copy of `mesh` (every done entry undone, then every entry
/// redone), checking that each fits the mesh it meets and that the oldest and newest meshes
/// are valid: a history that belongs to another mesh is an error here, not a panic at undo.
fn check_history(history: &History, mesh: &Mesh) -> Result<(), String> {
    let entries = history.entries();
    let mut replay = mesh.clone();
    for (i, entry) in entries[..history.done()].iter().enumerate().rev() {
        if !entry.mesh.fits_after(&replay) {
            return Err(format!("history entry {} does not fit the mesh", i + 1));
        }
        entry.mesh.undo(&mut replay);
    }
    replay
        .validate()
        .map_err(|e| format!("undoing the whole history gives a broken mesh: {e}"))?;
    for (i, entry) in entries.iter().enumerate() {
        if !entry.mesh.fits_before(&replay) {
            return Err(format!("history entry {} does not fit the mesh", i + 1));
        }
        entry.mesh.redo(&mut replay);
    }
    replay
        .validate()
        .map_err(|e| format!("redoing the whole history gives a broken mesh: {e}"))?;
    Ok(())
}

/// Whether `path` names a session file (by its `.slayer` extension).
pub fn is_session_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("slayer"))
}

/// Checks that `path` names a file [`save`] can write (`.slayer` or a mesh format), before any
/// work is done for it.
pub fn check_save_path(path: &Path) -> Result<(), IoError> {
    if is_session_path(path) {
        Ok(())
    } else {
        crate::io::Format::of_path(path).map(|_| ())
    }
}

/// Opens a session file, or a mesh file (OBJ, PLY, STL) as a new session, repaired where it needs
/// it.
pub fn open(path: &Path) -> Result<Session, SessionFileError> {
    open_with(path, &ImportOptions::default()).map(|(session, _)| session)
}

/// [`open`] with import options for a mesh file, and the import's report (empty for a
/// session file, which slayer wrote).
pub fn open_with(
    path: &Path,
    options: &ImportOptions,
) -> Result<(Session, ImportReport), SessionFileError> {
    if !is_session_path(path) {
        let (mesh, report) = crate::io::import_mesh(path, options)?;
        let mut session = Session::new(mesh);
        for &layer in &report.fuse_layers {
            session.layers[layer as usize].policy = ProximityPolicy::Fuse;
        }
        return Ok((session, report));
    }
    let bytes =
        crate::files::read_input(path, crate::files::MAX_INPUT_BYTES).map_err(|source| {
            IoError::Io {
                path: path.display().to_string(),
                source,
            }
        })?;
    let session = read_session(&bytes, &path.display().to_string())?;
    Ok((session, ImportReport::default()))
}

/// Saves a session atomically: a `.slayer` path gets the session file (with its history when
/// `with_history`), a mesh path (OBJ, PLY, STL) the mesh alone (a PLY with the layers that
/// fuse marked).
pub fn save(session: &Session, path: &Path, with_history: bool) -> Result<(), IoError> {
    let mut batch = AtomicBatch::new();
    stage(&mut batch, session, path, with_history)?;
    batch.commit()
}

/// [`save`] staged in `batch`, to be written with other files as one unit.
pub fn stage(
    batch: &mut AtomicBatch,
    session: &Session,
    path: &Path,
    with_history: bool,
) -> Result<(), IoError> {
    if is_session_path(path) {
        batch.stage(path, &write_session(session, with_history))
    } else {
        let fuse = session.all_fuse_layers();
        crate::io::stage_mesh_with(batch, &session.mesh, path, &fuse)
    }
}
