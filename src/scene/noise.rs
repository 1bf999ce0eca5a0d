//! Seeded smooth noise: a sum of plane waves with random directions and phases. Cheap, exactly
//! reproducible from the seed, and with a known bound on its slope, which keeps generated sheets
//! near-uniform after they are displaced.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

#[derive(Debug, Clone)]
pub struct WaveNoise {
    /// (direction x, direction y, angular frequency, phase, amplitude)
    waves: Vec<[f32; 5]>,
    amplitude_sum: f32,
}

impl WaveNoise {
    /// `count` waves with frequencies (cycles per unit length) drawn from `frequencies`.
    pub fn new(rng: &mut ChaCha8Rng, count: usize, frequencies: (f32, f32)) -> Self {
        let waves: Vec<[f32; 5]> = (0..count)
            .map(|_| {
                let angle = rng.random_range(0.0..std::f32::consts::TAU);
                let frequency = rng.random_range(frequencies.0..=frequencies.1);
                let phase = rng.random_range(0.0..std::f32::consts::TAU);
                // Higher frequencies get less weight, as in natural surfaces.
                let amplitude = 1.0 / frequency.max(1e-3);
                [
                    angle.cos(),
                    angle.sin(),
                    frequency * std::f32::consts::TAU,
                    phase,
                    amplitude,
                ]
            })
            .collect();
        let amplitude_sum = waves.iter().map(|w| w[4]).sum::<f32>().max(1e-6);
        WaveNoise {
            waves,
            amplitude_sum,
        }
    }

    /// Value in [-1, 1].
    pub fn at(&self, x: f32, y: f32) -> f32 {
        let mut sum = 0.0;
        for [dx, dy, omega, phase, amplitude] in &self.waves {
            sum += amplitude * (omega * (dx * x + dy * y) + phase).sin();
        }
        sum / self.amplitude_sum
    }

    /// An upper bound of |∇ value|.
    pub fn max_slope(&self) -> f32 {
        self.waves.iter().map(|w| w[2] * w[4]).sum::<f32>() / self.amplitude_sum
    }
}
