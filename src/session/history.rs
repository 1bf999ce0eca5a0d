//! Undo and redo: a list of entries, each what one user action changed (a [`MeshDelta`] and
//! the layer settings before and after), with a cursor between those done and those undone.

use super::LayerSettings;
use crate::mesh::{Mesh, MeshDelta};

/// The history's memory cap unless the user sets one.
pub const DEFAULT_HISTORY_CAP_BYTES: usize = 512 << 20;

/// One user action, undoable.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    /// What the action was, for a menu or `slayer history` ("draw stroke", "rename layer").
    pub label: String,
    pub(super) mesh: MeshDelta,
    /// The layer settings before and after, when the action changed them.
    pub(super) layers: Option<(Vec<LayerSettings>, Vec<LayerSettings>)>,
}

impl Entry {
    pub(super) fn new(
        label: &str,
        mesh: MeshDelta,
        layers: Option<(Vec<LayerSettings>, Vec<LayerSettings>)>,
    ) -> Entry {
        Entry {
            label: label.to_string(),
            mesh,
            layers,
        }
    }

    /// Bytes the entry holds (what the memory cap counts).
    pub fn bytes(&self) -> usize {
        let layers = self.layers.as_ref().map_or(0, |(a, b)| {
            (a.len() + b.len()) * std::mem::size_of::<LayerSettings>()
        });
        self.label.len() + self.mesh.bytes() + layers
    }

    /// The vertices whose rows the entry touches: what a viewer re-uploads after undoing or
    /// redoing it.
    pub fn touched_vertices(&self) -> Vec<u32> {
        self.mesh.touched_vertices()
    }

    pub(super) fn undo(&self, mesh: &mut Mesh, layers: &mut Vec<LayerSettings>) {
        self.mesh.undo(mesh);
        if let Some((before, _)) = &self.layers {
            *layers = before.clone();
        }
    }

    pub(super) fn redo(&self, mesh: &mut Mesh, layers: &mut Vec<LayerSettings>) {
        self.mesh.redo(mesh);
        if let Some((_, after)) = &self.layers {
            *layers = after.clone();
        }
    }
}

/// The entries of a session, oldest first, and how many of them are done.
#[derive(Debug, Clone, PartialEq)]
pub struct History {
    entries: Vec<Entry>,
    /// Entries `..done` are applied to the mesh; `done..` were undone and can be redone.
    done: usize,
    bytes: usize,
    cap_bytes: usize,
    /// Entries dropped for the cap since the session began.
    dropped: usize,
}

impl Default for History {
    fn default() -> Self {
        History::with_cap(DEFAULT_HISTORY_CAP_BYTES)
    }
}

impl History {
    pub fn with_cap(cap_bytes: usize) -> History {
        History {
            entries: Vec::new(),
            done: 0,
            bytes: 0,
            cap_bytes,
            dropped: 0,
        }
    }

    /// Every entry, oldest first; the first [`History::done`] are applied.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    pub fn done(&self) -> usize {
        self.done
    }

    pub fn can_undo(&self) -> bool {
        self.done > 0
    }

    pub fn can_redo(&self) -> bool {
        self.done < self.entries.len()
    }

    /// Bytes held by all entries.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    pub fn cap_bytes(&self) -> usize {
        self.cap_bytes
    }

    /// Entries dropped for the memory cap so far.
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    /// Sets the cap and drops the oldest entries past it; returns how many went.
    pub fn set_cap(&mut self, cap_bytes: usize) -> usize {
        self.cap_bytes = cap_bytes;
        self.enforce_cap()
    }

    /// Adds a done entry after the done ones, dropping the undone ones (a new action after an
    /// undo starts a new branch), then the oldest past the cap; returns how many were dropped
    /// for the cap. An entry larger than the cap on its own is kept alone.
    pub(super) fn push(&mut self, entry: Entry) -> usize {
        for undone in self.entries.drain(self.done..) {
            self.bytes -= undone.bytes();
        }
        self.bytes += entry.bytes();
        self.entries.push(entry);
        self.done = self.entries.len();
        self.enforce_cap()
    }

    fn enforce_cap(&mut self) -> usize {
        let mut dropped = 0;
        while self.bytes > self.cap_bytes && self.entries.len() > 1 && self.done > 0 {
            let oldest = self.entries.remove(0);
            self.bytes -= oldest.bytes();
            self.done -= 1;
            dropped += 1;
        }
        self.dropped += dropped;
        dropped
    }

    /// The entry to undo next, moving the cursor back over it.
    pub(super) fn step_back(&mut self) -> Option<&Entry> {
        self.done = self.done.checked_sub(1)?;
        Some(&self.entries[self.done])
    }

    /// The entry to redo next, moving the cursor forward over it.
    pub(super) fn step_forward(&mut self) -> Option<&Entry> {
        let entry = self.entries.get(self.done)?;
        self.done += 1;
        Some(entry)
    }

    /// A history read from a file: `entries` with the first `done` applied.
    pub(super) fn restored(entries: Vec<Entry>, done: usize, cap_bytes: usize) -> History {
        let bytes = entries.iter().map(Entry::bytes).sum();
        History {
            entries,
            done,
            bytes,
            cap_bytes,
            dropped: 0,
        }
    }
}
