//! Host side of `wgsl/scan.wgsl` and `wgsl/scan_add.wgsl`: an exclusive prefix sum of any
//! length. Each level scans blocks of `SCAN_BLOCK` values and writes one sum per block; the
//! sums are scanned the same way until one block remains, then added back level by level. A
//! million values take three levels; nothing limits the length but the buffer size.

use super::{GpuContext, GpuError};
use crate::abi::{CountParams, SCAN_BLOCK};

/// Records an exclusive scan of the first `count` u32s of `values`, in place.
pub fn record_exclusive_scan(
    gpu: &GpuContext,
    encoder: &mut wgpu::CommandEncoder,
    values: &wgpu::Buffer,
    count: usize,
) -> Result<(), GpuError> {
    if count == 0 {
        return Ok(());
    }
    let scan = gpu.compute_pipeline("scan")?;
    let scan_add = gpu.compute_pipeline("scan_add")?;
    // levels[k] holds the values of level k; the top level fits one block. Its block sum goes
    // to a scratch word nobody reads.
    let mut levels = vec![(values.clone(), count)];
    loop {
        let &(_, n) = levels.last().expect("one level");
        let sums = n.div_ceil(SCAN_BLOCK as usize);
        levels.push((gpu.output_buffer::<u32>("scan block sums", sums), sums));
        if n <= SCAN_BLOCK as usize {
            break;
        }
    }
    let uniforms: Vec<wgpu::Buffer> = levels
        .iter()
        .map(|&(_, n)| gpu.uniform_buffer("scan params", &CountParams::new(n)))
        .collect();
    for k in 0..levels.len() - 1 {
        let (values, n) = &levels[k];
        let (sums, _) = &levels[k + 1];
        gpu.record_dispatch(
            encoder,
            &scan,
            "scan",
            &[&uniforms[k], values, sums],
            *n,
            SCAN_BLOCK,
        );
    }
    // The top level's scan already is final; below it, add the scanned block sums back.
    for k in (0..levels.len().saturating_sub(2)).rev() {
        let (values, n) = &levels[k];
        let (offsets, _) = &levels[k + 1];
        gpu.record_dispatch(
            encoder,
            &scan_add,
            "scan_add",
            &[&uniforms[k], values, offsets],
            *n,
            SCAN_BLOCK,
        );
    }
    Ok(())
}

/// Exclusive prefix sum of `values` on the GPU (wrapping, as u32 arithmetic does there).
pub fn run_exclusive_scan(gpu: &GpuContext, values: &[u32]) -> Result<Vec<u32>, GpuError> {
    gpu.check_binding::<u32>("scan values", values.len())?;
    let buffer = gpu.storage_buffer("scan values", values, true);
    let mut encoder = gpu.encoder("scan");
    record_exclusive_scan(gpu, &mut encoder, &buffer, values.len())?;
    gpu.submit(encoder);
    gpu.read_buffer(&buffer, values.len())
}
