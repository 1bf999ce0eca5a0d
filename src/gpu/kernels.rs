//! The GPU's selection and deformation behind the pipeline's [`StepKernels`] seam: the mesh is
//! uploaded once and kept (positions and normals re-sent when they changed, everything when the
//! topology did), the hash table is rebuilt on the GPU when positions moved, and each step
//! selects and deforms there. Collisions, the exact backstop and remeshing stay on the CPU
//! until the proximity kernel joins (issue 5).
//!
//! A GPU that fails mid-stroke (device lost, an allocation refused, a buffer past the
//! adapter's limits) is not fatal: the kernels keep why and finish on the CPU, and the
//! mesh — which only the CPU writes — is untouched by the failure.

use glam::Vec3;

use super::{
    BrushSphere, DeformBuffers, GpuContext, GpuError, GpuHashTable, GpuSelection, SelectedVertex,
    VertexBuffers, record_deform, record_select, smoothing_neighbours, table_size_for,
};
use crate::brush::Dab;
use crate::mesh::{Mesh, MeshVersion};
use crate::pipeline::step::StrokeState;
use crate::pipeline::{CpuKernels, StepKernels};

/// What lives on the GPU between steps.
struct Resident {
    version: MeshVersion,
    vertices: VertexBuffers,
    normals: wgpu::Buffer,
    neighbour_offsets: wgpu::Buffer,
    neighbours: wgpu::Buffer,
    selection: GpuSelection,
    /// The hash table, for the positions of `table_version`.
    table: Option<GpuHashTable>,
    table_version: u64,
    layer_count: usize,
}

pub struct GpuKernels {
    gpu: GpuContext,
    resident: Option<Resident>,
    /// Set once the GPU failed: why. Everything after runs on the CPU.
    failed: Option<String>,
    /// Test hook: fail as a lost device would after this many more GPU calls.
    fail_after: Option<usize>,
}

impl GpuKernels {
    pub fn new(gpu: GpuContext) -> GpuKernels {
        GpuKernels {
            gpu,
            resident: None,
            failed: None,
            fail_after: None,
        }
    }

    /// Makes the GPU calls after the next `calls` fail, as a lost device would: for tests of
    /// the fallback.
    pub fn fail_after(&mut self, calls: usize) {
        self.fail_after = Some(calls);
    }

    fn check_injected_failure(&mut self) -> Result<(), GpuError> {
        match &mut self.fail_after {
            Some(0) => Err(GpuError::Readback("device lost (simulated)".into())),
            Some(n) => {
                *n -= 1;
                Ok(())
            }
            None => Ok(()),
        }
    }

    /// Brings the GPU copy up to date with `mesh`.
    fn sync(&mut self, mesh: &Mesh) -> Result<(), GpuError> {
        let version = mesh.version();
        let gpu = &self.gpu;
        match &mut self.resident {
            Some(r)
                if r.version.topology == version.topology
                    && r.vertices.count == mesh.vertex_count()
                    && r.layer_count == mesh.layer_count() =>
            {
                let moved = r.version.positions != version.positions;
                let attributes = r.version.attributes != version.attributes;
                if moved {
                    gpu.queue.write_buffer(
                        &r.vertices.positions,
                        0,
                        bytemuck::cast_slice(mesh.positions()),
                    );
                }
                if attributes {
                    gpu.queue.write_buffer(
                        &r.vertices.flags,
                        0,
                        bytemuck::cast_slice(&flag_bits(mesh)),
                    );
                }
                // Normals follow the positions and carry no version of their own.
                if moved || attributes {
                    gpu.queue
                        .write_buffer(&r.normals, 0, bytemuck::cast_slice(mesh.normals()));
                }
                r.version = version;
            }
            _ => {
                let layers = mesh.vertex_layers().to_vec();
                let vertices =
                    VertexBuffers::upload(gpu, mesh.positions(), &layers, &flag_bits(mesh))?;
                let (offsets, neighbours) = smoothing_neighbours(mesh);
                gpu.check_binding::<u32>("smoothing neighbours", neighbours.len())?;
                self.resident = Some(Resident {
                    version,
                    normals: gpu.storage_buffer("normals", mesh.normals(), true),
                    neighbour_offsets: gpu.storage_buffer("neighbour offsets", &offsets, false),
                    neighbours: gpu.storage_buffer("neighbours", &neighbours, false),
                    selection: GpuSelection::new(gpu, mesh.vertex_count().max(1))?,
                    table: None,
                    table_version: u64::MAX,
                    layer_count: mesh.layer_count(),
                    vertices,
                });
            }
        }
        Ok(())
    }

    fn gpu_select(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
    ) -> Result<Vec<(u32, f32)>, GpuError> {
        self.check_injected_failure()?;
        self.sync(mesh)?;
        let gpu = &self.gpu;
        let Some(r) = self.resident.as_mut() else {
            return Ok(Vec::new());
        };
        let cell = state.grid.map_or(state.max_edge, |g| g.cell_size());
        let mut encoder = gpu.encoder("select");
        if r.table.is_none() || r.table_version != r.version.positions {
            r.table = Some(GpuHashTable::record(
                gpu,
                &mut encoder,
                &r.vertices.positions,
                &r.vertices.flags,
                r.vertices.count,
                1.0 / cell,
                table_size_for(r.vertices.count),
            )?);
            r.table_version = r.version.positions;
        }
        let active: Vec<u32> = state.active.iter().map(|&a| a as u32).collect();
        let active = gpu.storage_buffer("active layers", &active, false);
        let Some(table) = r.table.as_ref() else {
            return Ok(Vec::new());
        };
        record_select(
            gpu,
            &mut encoder,
            &r.vertices,
            &active,
            state.active.len(),
            table,
            &BrushSphere {
                center: dab.frame.center,
                radius: dab.brush.radius,
                falloff: dab.brush.falloff,
            },
            &r.selection,
        )?;
        gpu.queue.submit([encoder.finish()]);
        let mut selected: Vec<(u32, f32)> = r
            .selection
            .read(gpu)?
            .into_iter()
            .map(|s| (s.vertex, s.weight))
            .collect();
        // The kernel appends in whatever order its threads ran; the pipeline sums in vertex
        // order so that every backend gets the same bits.
        selected.sort_unstable_by_key(|&(v, _)| v);
        Ok(selected)
    }

    fn gpu_deform(
        &mut self,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
    ) -> Result<Vec<Vec3>, GpuError> {
        self.check_injected_failure()?;
        self.sync(mesh)?;
        if selection.is_empty() {
            return Ok(Vec::new());
        }
        let gpu = &self.gpu;
        let Some(r) = self.resident.as_ref() else {
            return Ok(Vec::new());
        };
        let entries: Vec<SelectedVertex> = selection
            .iter()
            .map(|&(vertex, weight)| SelectedVertex { vertex, weight })
            .collect();
        let selected = gpu.storage_buffer("selected", &entries, false);
        let count = gpu.storage_buffer("selection count", &[entries.len() as u32], false);
        let targets = gpu.output_buffer::<Vec3>("targets", entries.len());
        let mut encoder = gpu.encoder("deform");
        record_deform(
            gpu,
            &mut encoder,
            &DeformBuffers {
                positions: &r.vertices.positions,
                normals: &r.normals,
                selected: &selected,
                selection_count: &count,
                neighbour_offsets: &r.neighbour_offsets,
                neighbours: &r.neighbours,
            },
            dab,
            entries.len(),
            &targets,
        )?;
        gpu.queue.submit([encoder.finish()]);
        gpu.read_buffer::<Vec3>(&targets, entries.len())
    }

    /// Gives the GPU up for good, keeping why (the pipeline reports it).
    fn give_up(&mut self, error: GpuError) {
        self.failed = Some(error.to_string());
        self.resident = None;
    }
}

/// The vertex flags as the kernels read them, one `u32` each.
fn flag_bits(mesh: &Mesh) -> Vec<u32> {
    mesh.flags().iter().map(|f| f.bits()).collect()
}

impl StepKernels for GpuKernels {
    fn name(&self) -> String {
        self.gpu.adapter.name.clone()
    }

    fn failure(&self) -> Option<String> {
        self.failed.clone()
    }

    fn select(&mut self, state: &StrokeState<'_>, mesh: &Mesh, dab: &Dab) -> Vec<(u32, f32)> {
        if self.failed.is_none() {
            match self.gpu_select(state, mesh, dab) {
                Ok(selection) => return selection,
                Err(error) => self.give_up(error),
            }
        }
        CpuKernels.select(state, mesh, dab)
    }

    fn deform(
        &mut self,
        state: &StrokeState<'_>,
        mesh: &Mesh,
        dab: &Dab,
        selection: &[(u32, f32)],
    ) -> Vec<Vec3> {
        if self.failed.is_none() {
            match self.gpu_deform(mesh, dab, selection) {
                Ok(targets) => return targets,
                Err(error) => self.give_up(error),
            }
        }
        CpuKernels.deform(state, mesh, dab, selection)
    }
}
