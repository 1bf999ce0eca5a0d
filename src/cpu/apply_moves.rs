//! Mirror of `wgsl/apply_moves.wgsl`: the writes around the proximity passes, by mode.

use super::shared::{invocations, packed_position};
use glam::Vec3;

use crate::abi::{ApplyMode, ApplyParams, MovingVertex, PULL_SCALE};
use crate::mesh::INVALID;

/// What the kernel binds besides its parameters.
pub struct ApplyBuffers<'a> {
    pub moving: &'a [MovingVertex],
    /// Packed x, y, z, one per entry.
    pub targets: &'a [f32],
    /// Per entry: the proximity pass's pull-back amount, or zero.
    pub pulls: &'a mut [u32],
    /// Packed x, y, z per vertex.
    pub positions: &'a mut [f32],
    pub marks: &'a mut [u32],
    pub next_count: &'a mut u32,
    /// Packed x, y, z, one per entry.
    pub finals: &'a mut [f32],
}

fn set_position(positions: &mut [f32], v: u32, p: [f32; 3]) {
    let i = 3 * v as usize;
    positions[i..i + 3].copy_from_slice(&p);
}

pub fn apply_moves(params: &ApplyParams, buffers: &mut ApplyBuffers<'_>) {
    let place = ApplyMode::Place as u32;
    let pull = ApplyMode::Pull as u32;
    let pull_last = ApplyMode::PullLast as u32;
    let mark_moved = ApplyMode::MarkMoved as u32;
    let clear = ApplyMode::Clear as u32;
    for i in invocations(params.count) {
        let entry = &buffers.moving[i as usize];
        let v = entry.vertex;
        if v == INVALID {
            continue;
        }
        match params.mode {
            mode if mode == place => {
                let target = packed_position(buffers.targets, i).to_array();
                set_position(buffers.positions, v, target);
                buffers.marks[v as usize] = 0;
                buffers.pulls[i as usize] = 0;
            }
            mode if mode == pull || mode == pull_last => {
                let pull = buffers.pulls[i as usize];
                if pull != 0 {
                    let start = Vec3::from_array(entry.start);
                    let to = if mode == pull_last {
                        start
                    } else {
                        let t = (65536 - pull) as f32 / PULL_SCALE;
                        start + (packed_position(buffers.positions, v) - start) * t
                    };
                    set_position(buffers.positions, v, to.to_array());
                    buffers.marks[v as usize] = 1;
                    buffers.pulls[i as usize] = 0;
                    *buffers.next_count = params.next_invocations;
                } else {
                    buffers.marks[v as usize] = 0;
                }
            }
            mode if mode == mark_moved => {
                let moved = packed_position(buffers.positions, v) != Vec3::from_array(entry.start);
                buffers.marks[v as usize] = if moved { i + 1 } else { 0 };
            }
            mode if mode == clear => buffers.marks[v as usize] = 0,
            _ => {
                let p = packed_position(buffers.positions, v).to_array();
                set_position(buffers.finals, i, p);
                buffers.marks[v as usize] = 0;
                buffers.pulls[i as usize] = 0;
            }
        }
    }
}
