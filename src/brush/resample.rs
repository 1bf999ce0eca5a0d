//! Resampling a stroke at its spacing, bounded: the samples a user gives become dabs every
//! `spacing × radius` of arc length, never more than a stroke's bound.

use glam::Vec3;
use thiserror::Error;

use super::Sample;

/// The most dabs (samples after resampling) one stroke may make. Two samples far apart would
/// otherwise resample into dabs without end; the bound is checked before a segment emits any.
/// Raise it with [`PipelineSettings::max_dabs_per_stroke`](crate::pipeline::PipelineSettings)
/// (`slayer sculpt --max-dabs`).
pub const MAX_DABS_PER_STROKE: usize = 100_000;

/// A stroke would make more dabs than its bound allows.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[error(
    "the stroke would make about {wanted:.0} dabs (its samples span {length} world units at a \
     step of {step}), more than the {limit} allowed; raise the dab bound (`--max-dabs`, \
     PipelineSettings::max_dabs_per_stroke) or split the stroke"
)]
pub struct DabLimit {
    /// Dabs the stroke would make with the refused samples.
    pub wanted: f64,
    /// The stroke's length with them.
    pub length: f64,
    pub step: f32,
    pub limit: usize,
}

/// Resamples a polyline of samples every `step` of arc length, interpolating pressure and
/// normal; the first and last samples are kept. The whole of [`Resampler`] in one call, bound
/// by [`MAX_DABS_PER_STROKE`].
pub fn resample(samples: &[Sample], step: f32) -> Result<Vec<Sample>, DabLimit> {
    let mut resampler = Resampler::new(step);
    let mut out = Vec::new();
    for &sample in samples {
        resampler.push(sample, &mut out)?;
    }
    resampler.finish(&mut out);
    Ok(out)
}

/// How many dabs `samples` make at `step` (at most; the exact count the resampler emits is this
/// or one less): for checking a stroke against a bound before it runs.
pub fn dabs_for(samples: &[Sample], step: f32) -> f64 {
    if step.is_nan() || step <= 0.0 {
        return samples.len() as f64;
    }
    let length: f64 = samples
        .windows(2)
        .map(|w| w[0].position.as_dvec3().distance(w[1].position.as_dvec3()))
        .sum();
    (length / step as f64).floor() + 2.0
}

/// Resamples a stroke while it is drawn: samples are pushed as they arrive, and each push
/// emits the samples every `step` of arc length that the new segment completes. The last
/// input sample is emitted by [`Resampler::finish`] (only then is it known to be the last),
/// unless an emission already lies on it. Pushing samples one at a time or all at once
/// emits the same samples, bit for bit: the arithmetic is per segment. A push that would take
/// the stroke past its dab bound emits nothing and changes nothing.
#[derive(Debug, Clone)]
pub struct Resampler {
    step: f32,
    /// The last sample pushed, and where the last emitted one lies.
    last_input: Option<Sample>,
    last_emitted: Option<Vec3>,
    /// Arc length since the last emission.
    carried: f32,
    /// Samples emitted so far, the bound on them, and the arc length pushed (for messages).
    emitted: usize,
    limit: usize,
    length: f64,
}

impl Resampler {
    /// A resampler bound by [`MAX_DABS_PER_STROKE`]. A step that is not a positive number
    /// passes every sample through as it is.
    pub fn new(step: f32) -> Resampler {
        Resampler::with_limit(step, MAX_DABS_PER_STROKE)
    }

    /// A resampler that emits at most `limit` samples, the last one included.
    pub fn with_limit(step: f32, limit: usize) -> Resampler {
        Resampler {
            step,
            last_input: None,
            last_emitted: None,
            carried: 0.0,
            emitted: 0,
            limit,
            length: 0.0,
        }
    }

    fn passes_through(&self) -> bool {
        self.step.is_nan() || self.step <= 0.0
    }

    /// Emits into `out` the samples the segment up to `sample` completes, or refuses the
    /// sample (and emits nothing) when they would take the stroke past its bound.
    pub fn push(&mut self, sample: Sample, out: &mut Vec<Sample>) -> Result<(), DabLimit> {
        let previous = self.last_input;
        // The f32 length the segment is walked with, so that the count matches the walk.
        let segment = previous.map_or(0.0, |a| a.position.distance(sample.position));
        let emissions = self.emissions(segment, previous.is_none());
        // One place is kept for the sample `finish` may add.
        let wanted = self.emitted as f64 + emissions + 1.0;
        if wanted > self.limit as f64 {
            return Err(DabLimit {
                wanted,
                length: self.length + segment as f64,
                step: self.step,
                limit: self.limit,
            });
        }
        let before = out.len();
        self.emit(sample, out, emissions as usize);
        self.emitted += out.len() - before;
        self.length += segment as f64;
        Ok(())
    }

    /// How many samples a segment of `length` emits at most (one more than the exact count
    /// allows for the walk's rounding), in f64 so that an absurd length is counted, not walked.
    fn emissions(&self, length: f32, first: bool) -> f64 {
        if first || self.passes_through() {
            return 1.0;
        }
        let (length, step) = (length as f64, self.step as f64);
        let at = step - self.carried as f64;
        if length <= 0.0 || at > length + step {
            return 0.0;
        }
        ((length - at) / step).floor().max(0.0) + 2.0
    }

    /// Emits at most `cap` samples: f32 rounding may not add one the f64 count missed.
    fn emit(&mut self, sample: Sample, out: &mut Vec<Sample>, cap: usize) {
        let previous = self.last_input.replace(sample);
        let Some(a) = previous.filter(|_| !self.passes_through()) else {
            out.push(sample);
            self.last_emitted = Some(sample.position);
            return;
        };
        let b = sample;
        let step = self.step;
        let length = a.position.distance(b.position);
        let mut at = step - self.carried; // distance along this segment of the next emission
        let mut count = 0;
        while at <= length && length > 0.0 && count < cap {
            count += 1;
            let t = at / length;
            let emitted = Sample {
                position: a.position.lerp(b.position, t),
                pressure: a.pressure + (b.pressure - a.pressure) * t,
                normal: match (a.normal, b.normal) {
                    (Some(na), Some(nb)) => na.lerp(nb, t).try_normalize().or(Some(na)),
                    (n, None) | (None, n) => n,
                },
            };
            self.last_emitted = Some(emitted.position);
            out.push(emitted);
            at += step;
        }
        // Below `step` unless the cap cut the walk short: then the next segment starts afresh.
        self.carried = (length - (at - step)).min(step);
    }

    /// Emits the last sample pushed, unless the last emission lies on it. Pushing after this
    /// starts a new segment from that sample.
    pub fn finish(&mut self, out: &mut Vec<Sample>) {
        let (Some(last), Some(emitted)) = (self.last_input, self.last_emitted) else {
            return;
        };
        if !self.passes_through() && emitted.distance(last.position) > 1e-3 * self.step {
            out.push(last);
            self.last_emitted = Some(last.position);
            self.emitted += 1;
        }
    }
}
