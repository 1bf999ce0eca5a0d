//! Adapter choice and the device every kernel runs on.
//!
//! Preference: a hardware GPU, then (only when software is allowed) a CPU rasterizer such as
//! Mesa's lavapipe; `WGPU_ADAPTER_NAME` pins an adapter by name. Vulkan wins over GL for the
//! same device.

use std::sync::mpsc;

use bytemuck::Pod;
use thiserror::Error;
use wgpu::util::DeviceExt;

use super::options::GpuOptions;

#[derive(Debug, Error)]
pub enum GpuError {
    #[error("no GPU adapter found{0}")]
    NoAdapter(String),
    #[error("only a software adapter is available ({0}); allow software adapters to use it")]
    OnlySoftware(String),
    #[error("the adapter refused a device: {0}")]
    RequestDevice(#[from] wgpu::RequestDeviceError),
    #[error("reading back a GPU buffer failed: {0}")]
    Readback(String),
    #[error("GPU validation error: {0}")]
    Validation(String),
    #[error(transparent)]
    Shader(#[from] super::shaders::ShaderError),
    #[error(
        "the mesh needs about {needed_mib} MiB on the GPU, over the budget of {budget_mib} MiB \
         (SLAYER_GPU_BUDGET_MIB raises it)"
    )]
    OverBudget { needed_mib: u64, budget_mib: u64 },
    #[error(
        "{what} needs {bytes} bytes in one storage binding; the adapter allows {limit} \
         (the mesh is too large for this adapter's limits)"
    )]
    TooLarge {
        what: String,
        bytes: u64,
        limit: u64,
    },
}

/// Fails clearly when `bytes` pass `limit`.
pub(super) fn check_fits(what: &str, bytes: u64, limit: u64) -> Result<(), GpuError> {
    if bytes > limit {
        return Err(GpuError::TooLarge {
            what: what.to_string(),
            bytes,
            limit,
        });
    }
    Ok(())
}

/// How many workgroups a dispatch runs.
#[derive(Debug, Clone, Copy)]
pub enum Workgroups<'a> {
    /// Enough to cover `invocations` threads (none for zero).
    Cover {
        invocations: usize,
        workgroup_size: u32,
    },
    /// Read by the GPU from three `u32`s an earlier pass wrote (see `dispatch_args`).
    Indirect(&'a wgpu::Buffer),
}

/// Which adapters may be used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AdapterChoice {
    /// Accept a CPU rasterizer (lavapipe, llvmpipe) when no hardware GPU is present.
    pub allow_software: bool,
}

/// What a user needs to know about an adapter.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AdapterSummary {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub software: bool,
}

impl AdapterSummary {
    fn of(info: &wgpu::AdapterInfo) -> Self {
        AdapterSummary {
            name: info.name.clone(),
            backend: format!("{:?}", info.backend),
            device_type: format!("{:?}", info.device_type),
            driver: format!("{} {}", info.driver, info.driver_info)
                .trim()
                .to_string(),
            software: info.device_type == wgpu::DeviceType::Cpu,
        }
    }
}

impl std::fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}, {}{})",
            self.name,
            self.backend,
            self.device_type,
            if self.driver.is_empty() {
                String::new()
            } else {
                format!(", {}", self.driver)
            }
        )
    }
}

/// Vulkan, Metal and DX12 by default (GL lacks what the kernels need and its EGL probing is
/// noisy on headless machines); `WGPU_BACKEND` overrides.
fn instance() -> wgpu::Instance {
    let descriptor = wgpu::InstanceDescriptor {
        backends: wgpu::Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    };
    wgpu::Instance::new(descriptor.with_env())
}

/// Higher is better.
fn rank(info: &wgpu::AdapterInfo) -> u32 {
    let device = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 40,
        wgpu::DeviceType::IntegratedGpu => 30,
        wgpu::DeviceType::VirtualGpu => 20,
        wgpu::DeviceType::Cpu => 10,
        wgpu::DeviceType::Other => 0,
    };
    let backend = match info.backend {
        wgpu::Backend::Vulkan | wgpu::Backend::Metal | wgpu::Backend::Dx12 => 2,
        wgpu::Backend::Gl => 1,
        _ => 0,
    };
    device + backend
}

/// Every adapter wgpu can see, best first.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let mut adapters = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()));
    adapters.sort_by_key(|a| std::cmp::Reverse(rank(&a.get_info())));
    adapters
        .iter()
        .map(|a| AdapterSummary::of(&a.get_info()))
        .collect()
}

/// A device and queue on the chosen adapter.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: AdapterSummary,
    /// The instance and adapter the device came from: a window that shares the device (the
    /// app's) makes its surface with them.
    pub instance: wgpu::Instance,
    pub wgpu_adapter: wgpu::Adapter,
    pub limits: wgpu::Limits,
    /// How much GPU memory a backend may keep resident, in bytes: our own budget, because
    /// lavapipe never reports running out (it takes host memory until the process dies) and
    /// wgpu does not say how much a device has. [`GpuOptions::budget_mib`] sets it; the default is
    /// [`super::DEFAULT_GPU_BUDGET_MIB`].
    pub budget_bytes: u64,
    /// Compiled kernels by name: validating and compiling a kernel takes milliseconds, and a
    /// backend records the same few kernels for every step of every stroke.
    pipelines: std::sync::Mutex<std::collections::HashMap<String, wgpu::ComputePipeline>>,
    /// Blocking read-backs so far (each a submission the CPU waited for): the figure that one
    /// submission per step saves, whatever the adapter's speed.
    read_backs: std::sync::atomic::AtomicUsize,
    /// Submissions so far ([`GpuContext::submit`]).
    submissions: std::sync::atomic::AtomicUsize,
    /// Microseconds the CPU spent in submissions and blocked waiting for the GPU: where a
    /// hardware GPU's time goes when the kernels are not the cost.
    submit_micros: std::sync::atomic::AtomicU64,
    waited_micros: std::sync::atomic::AtomicU64,
}

impl GpuContext {
    /// Opens the best adapter allowed by `choice`, with every limit the adapter offers.
    pub fn new(choice: AdapterChoice) -> Result<GpuContext, GpuError> {
        GpuContext::with_limits(choice, |_| {})
    }

    /// Opens the best adapter `options` allow (software ones, one by name), with every limit
    /// the adapter offers and the options' memory budget.
    pub fn open(options: &GpuOptions) -> Result<GpuContext, GpuError> {
        GpuContext::open_with_limits(options, |_| {})
    }

    /// As [`GpuContext::new`], with the device's limits lowered by `lower` first: the device
    /// then enforces them, which is how tests check that large buffers are split to fit (say,
    /// a storage binding of a few KiB instead of lavapipe's 128 MiB). Raising a limit past the
    /// adapter's fails as `RequestDevice`.
    pub fn with_limits(
        choice: AdapterChoice,
        lower: impl FnOnce(&mut wgpu::Limits),
    ) -> Result<GpuContext, GpuError> {
        let options = GpuOptions {
            allow_software: choice.allow_software,
            ..GpuOptions::default()
        };
        GpuContext::open_with_limits(&options, lower)
    }

    fn open_with_limits(
        options: &GpuOptions,
        lower: impl FnOnce(&mut wgpu::Limits),
    ) -> Result<GpuContext, GpuError> {
        let instance = instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let pinned = options.adapter_name.clone().filter(|s| !s.is_empty());
        if let Some(name) = &pinned {
            let wanted = name.to_lowercase();
            adapters.retain(|a| a.get_info().name.to_lowercase().contains(&wanted));
        }
        adapters.sort_by_key(|a| std::cmp::Reverse(rank(&a.get_info())));
        let Some(adapter) = adapters.into_iter().next() else {
            let detail = match pinned {
                Some(name) => format!(" matching WGPU_ADAPTER_NAME={name}"),
                None => " (is a Vulkan driver installed? `tools/test.sh` installs Mesa's lavapipe)"
                    .into(),
            };
            return Err(GpuError::NoAdapter(detail));
        };
        let info = adapter.get_info();
        let summary = AdapterSummary::of(&info);
        if summary.software && !options.allow_software {
            return Err(GpuError::OnlySoftware(summary.to_string()));
        }
        let mut limits = adapter.limits();
        lower(&mut limits);
        let (device, queue) =
            pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("slayer"),
                required_features: wgpu::Features::empty(),
                required_limits: limits.clone(),
                ..Default::default()
            }))?;
        let budget_mib = options.budget_mib;
        Ok(GpuContext {
            device,
            queue,
            adapter: summary,
            instance,
            wgpu_adapter: adapter,
            limits,
            budget_bytes: budget_mib << 20,
            pipelines: Default::default(),
            read_backs: Default::default(),
            submissions: Default::default(),
            submit_micros: Default::default(),
            waited_micros: Default::default(),
        })
    }

    /// A compute pipeline for kernel `name` (entry point `main`, layout from the shader),
    /// compiled on first use and kept. Kernels with a paged array (`shared/pages`) are
    /// compiled for the page size the limits give now, and kept per page size.
    pub fn compute_pipeline(&self, name: &str) -> Result<wgpu::ComputePipeline, GpuError> {
        let key = format!("{name}@{}", super::limits::page_shift(&self.limits));
        let cached = self
            .pipelines
            .lock()
            .ok()
            .and_then(|p| p.get(&key).cloned());
        if let Some(pipeline) = cached {
            return Ok(pipeline);
        }
        let pipeline = self.compile_pipeline(name)?;
        if let Ok(mut pipelines) = self.pipelines.lock() {
            pipelines.insert(key, pipeline.clone());
        }
        Ok(pipeline)
    }

    fn compile_pipeline(&self, name: &str) -> Result<wgpu::ComputePipeline, GpuError> {
        let source = super::shaders::kernel_source(name)?;
        let shift = super::limits::page_shift(&self.limits) as f64;
        let page_shift = [(crate::abi::PAGE_SHIFT_CONSTANT, shift)];
        let constants: &[(&str, f64)] = if source.contains(crate::abi::PAGE_SHIFT_CONSTANT) {
            &page_shift
        } else {
            &[]
        };
        // Validate with naga first: its messages carry source locations.
        super::shaders::validate(name, &source)?;
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = self
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(name),
                layout: None,
                module: &module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            });
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Validation(error.to_string()));
        }
        Ok(pipeline)
    }

    /// A storage buffer holding `data`, zero-padded to at least one element and a multiple of 4
    /// bytes, so that an empty input still binds as an array of its type.
    pub fn storage_buffer<T: Pod>(&self, label: &str, data: &[T], writable: bool) -> wgpu::Buffer {
        let mut usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        if writable {
            usage |= wgpu::BufferUsages::COPY_DST;
        }
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let size = bytes
            .len()
            .max(std::mem::size_of::<T>())
            .next_multiple_of(4)
            .max(4);
        let mut padded;
        let contents = if bytes.len() == size {
            bytes
        } else {
            padded = vec![0u8; size];
            padded[..bytes.len()].copy_from_slice(bytes);
            &padded[..]
        };
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
    }

    /// A storage buffer the host writes, with room for `capacity` elements of `T`: the first
    /// hold `data`, the rest are zero.
    pub fn storage_buffer_with_room<T: Pod>(
        &self,
        label: &str,
        data: &[T],
        capacity: usize,
    ) -> wgpu::Buffer {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let size = (capacity.max(data.len()) * std::mem::size_of::<T>()).max(4);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.next_multiple_of(4) as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        if !bytes.is_empty() {
            self.queue.write_buffer(&buffer, 0, bytes);
        }
        buffer
    }

    /// A zeroed storage buffer for `count` elements of `T`.
    pub fn output_buffer<T: Pod>(&self, label: &str, count: usize) -> wgpu::Buffer {
        self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (count * std::mem::size_of::<T>()).max(4) as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    pub fn uniform_buffer<T: Pod>(&self, label: &str, value: &T) -> wgpu::Buffer {
        self.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytemuck::bytes_of(value),
                usage: wgpu::BufferUsages::UNIFORM,
            })
    }

    /// Copies the first `count` elements of `buffer` back to the CPU.
    pub fn read_buffer<T: Pod>(
        &self,
        buffer: &wgpu::Buffer,
        count: usize,
    ) -> Result<Vec<T>, GpuError> {
        let size = (count * std::mem::size_of::<T>()) as u64;
        if size == 0 {
            return Ok(Vec::new());
        }
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.submit(encoder);
        let bytes = self.map_read(&staging)?;
        Ok(bytemuck::pod_collect_to_vec::<u8, T>(&bytes))
    }

    /// Submits what `encoder` recorded, counting the submission: per stroke sample it is, with
    /// the blocking read-backs, the cost a hardware GPU pays beside its kernels.
    pub fn submit(&self, encoder: wgpu::CommandEncoder) {
        self.submissions
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let started = std::time::Instant::now();
        self.queue.submit([encoder.finish()]);
        add_micros(&self.submit_micros, started);
    }

    /// Submissions so far ([`GpuContext::submit`]).
    pub fn submissions(&self) -> usize {
        self.submissions.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Microseconds spent so far in submissions and in blocking waits for the GPU.
    pub fn host_micros(&self) -> (u64, u64) {
        let load = |m: &std::sync::atomic::AtomicU64| m.load(std::sync::atomic::Ordering::Relaxed);
        (load(&self.submit_micros), load(&self.waited_micros))
    }

    /// Waits until the GPU has done everything submitted so far.
    pub fn wait(&self) -> Result<(), GpuError> {
        let started = std::time::Instant::now();
        let waited = self
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()));
        add_micros(&self.waited_micros, started);
        waited
    }

    /// Waits for the GPU and copies a mappable (`MAP_READ`) buffer's bytes out.
    pub fn map_read(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
        self.read_backs
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let started = std::time::Instant::now();
        let bytes = map_read(&self.device, buffer);
        add_micros(&self.waited_micros, started);
        bytes
    }

    /// Blocking read-backs so far ([`GpuContext::map_read`] calls).
    pub fn read_backs(&self) -> usize {
        self.read_backs.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Fails clearly when keeping `bytes` resident would pass the budget; checked before
    /// anything is allocated.
    pub fn check_budget(&self, bytes: u64) -> Result<(), GpuError> {
        if bytes > self.budget_bytes {
            return Err(GpuError::OverBudget {
                needed_mib: bytes.div_ceil(1 << 20),
                budget_mib: self.budget_bytes >> 20,
            });
        }
        Ok(())
    }

    /// Fails clearly when `count` elements of `T` would not fit one storage binding (lavapipe
    /// allows 128 MiB); checked before anything is allocated.
    pub fn check_binding<T>(&self, what: &str, count: usize) -> Result<(), GpuError> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        let limit = self
            .limits
            .max_storage_buffer_binding_size
            .min(self.limits.max_buffer_size);
        check_fits(what, bytes, limit)
    }

    /// Records one dispatch of `pipeline` covering `invocations` threads, its bind group 0
    /// binding `resources[i]` at binding `i` (every kernel declares its bindings in that order).
    /// Nothing is recorded for zero invocations, so empty inputs need no special case.
    pub fn record_dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        label: &str,
        resources: &[&wgpu::Buffer],
        invocations: usize,
        workgroup_size: u32,
    ) {
        let workgroups = Workgroups::Cover {
            invocations,
            workgroup_size,
        };
        self.record_paged_dispatch(encoder, pipeline, label, resources, &[], workgroups);
    }

    /// As [`GpuContext::record_dispatch`], with the workgroup counts read by the GPU from
    /// `args` (three `u32`s an earlier pass wrote, see `dispatch_args`).
    pub fn record_dispatch_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        label: &str,
        resources: &[&wgpu::Buffer],
        args: &wgpu::Buffer,
    ) {
        let workgroups = Workgroups::Indirect(args);
        self.record_paged_dispatch(encoder, pipeline, label, resources, &[], workgroups);
    }

    /// As [`GpuContext::record_dispatch`] (or `_indirect`) for a kernel with paged arrays
    /// (see [`super::pages`]): `paged[k]` is bound page by page as bind group `k + 1`.
    pub fn record_paged_dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::ComputePipeline,
        label: &str,
        resources: &[&wgpu::Buffer],
        paged: &[&wgpu::Buffer],
        workgroups: Workgroups<'_>,
    ) {
        if let Workgroups::Cover { invocations: 0, .. } = workgroups {
            return;
        }
        let pages: Vec<wgpu::BindGroup> = paged
            .iter()
            .enumerate()
            .map(|(k, buffer)| {
                let device = (&self.device, &self.limits);
                super::limits::page_bind_group(device, pipeline, k as u32 + 1, label, buffer)
            })
            .collect();
        let entries: Vec<wgpu::BindGroupEntry<'_>> = resources
            .iter()
            .enumerate()
            .map(|(i, buffer)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        for (k, group) in pages.iter().enumerate() {
            pass.set_bind_group(k as u32 + 1, group, &[]);
        }
        match workgroups {
            Workgroups::Cover {
                invocations,
                workgroup_size,
            } => {
                let (x, y) = self.dispatch_size(invocations, workgroup_size);
                pass.dispatch_workgroups(x, y, 1);
            }
            Workgroups::Indirect(args) => pass.dispatch_workgroups_indirect(args, 0),
        }
    }

    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }

    /// Workgroup counts covering `invocations` threads of `workgroup_size`, folded into y when
    /// x would pass the adapter's per-dimension limit (kernels flatten with `flat_index`).
    pub fn dispatch_size(&self, invocations: usize, workgroup_size: u32) -> (u32, u32) {
        let groups = invocations.div_ceil(workgroup_size as usize) as u64;
        let max_x = self.limits.max_compute_workgroups_per_dimension.max(1) as u64;
        if groups <= max_x {
            (groups as u32, 1)
        } else {
            (max_x as u32, groups.div_ceil(max_x) as u32)
        }
    }
}

fn add_micros(total: &std::sync::atomic::AtomicU64, since: std::time::Instant) {
    let micros = since.elapsed().as_micros() as u64;
    total.fetch_add(micros, std::sync::atomic::Ordering::Relaxed);
}

/// [`GpuContext::map_read`] on any device (a window's), uncounted.
pub(crate) fn map_read(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let (sender, receiver) = mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |result| {
        let _ = sender.send(result);
    });
    let failed = |e: &dyn std::fmt::Display| GpuError::Readback(e.to_string());
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| failed(&e))?;
    receiver
        .recv()
        .map_err(|e| failed(&e))?
        .map_err(|e| failed(&e))?;
    let bytes = buffer
        .get_mapped_range(..)
        .map_err(|e| failed(&e))?
        .to_vec();
    buffer.unmap();
    Ok(bytes)
}
