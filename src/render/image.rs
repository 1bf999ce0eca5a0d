//! Rendered images: 8-bit sRGB RGBA pixels, PNG in and out, and the comparison the reference
//! image test uses.

use std::path::Path;

use thiserror::Error;

#[derive(Debug, Error)]
pub enum ImageError {
    #[error("{path}: {message}")]
    Decode { path: String, message: String },
    #[error("encoding PNG: {0}")]
    Encode(String),
    #[error("images differ in size: {0}×{1} and {2}×{3}")]
    SizeMismatch(u32, u32, u32, u32),
}

/// An image, rows top to bottom, 4 bytes a pixel (sRGB-encoded RGB, linear alpha).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// How far two images are apart, per channel value (0–255).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageDifference {
    /// Mean absolute difference over every RGB channel value.
    pub mean: f64,
    /// Largest absolute difference of any channel.
    pub max: u8,
    /// Pixels with some channel differing by more than the threshold asked for.
    pub pixels_over: usize,
}

impl Image {
    /// An image filled with one colour.
    pub fn filled(width: u32, height: u32, rgba: [u8; 4]) -> Image {
        Image {
            width,
            height,
            rgba: rgba.repeat(width as usize * height as usize),
        }
    }

    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = 4 * (y as usize * self.width as usize + x as usize);
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// PNG bytes.
    pub fn to_png(&self) -> Result<Vec<u8>, ImageError> {
        use image::ImageEncoder;
        let mut bytes = Vec::new();
        image::codecs::png::PngEncoder::new(&mut bytes)
            .write_image(
                &self.rgba,
                self.width,
                self.height,
                image::ExtendedColorType::Rgba8,
            )
            .map_err(|e| ImageError::Encode(e.to_string()))?;
        Ok(bytes)
    }

    /// Decodes a PNG (any bit depth or colour type) into 8-bit RGBA; `name` is used in messages.
    pub fn from_png(bytes: &[u8], name: &str) -> Result<Image, ImageError> {
        let decoded = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
            .map_err(|e| ImageError::Decode {
                path: name.to_string(),
                message: e.to_string(),
            })?
            .into_rgba8();
        Ok(Image {
            width: decoded.width(),
            height: decoded.height(),
            rgba: decoded.into_raw(),
        })
    }

    /// Reads a PNG file.
    pub fn read_png(path: &Path) -> Result<Image, ImageError> {
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| ImageError::Decode {
            path: name.clone(),
            message: e.to_string(),
        })?;
        Image::from_png(&bytes, &name)
    }

    /// Compares the RGB channels of two images of the same size; `threshold` decides which
    /// pixels count in [`ImageDifference::pixels_over`].
    pub fn difference(&self, other: &Image, threshold: u8) -> Result<ImageDifference, ImageError> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(ImageError::SizeMismatch(
                self.width,
                self.height,
                other.width,
                other.height,
            ));
        }
        let mut sum = 0u64;
        let mut max = 0u8;
        let mut pixels_over = 0;
        for (a, b) in self.rgba.chunks_exact(4).zip(other.rgba.chunks_exact(4)) {
            let mut over = false;
            for k in 0..3 {
                let d = a[k].abs_diff(b[k]);
                sum += d as u64;
                max = max.max(d);
                over |= d > threshold;
            }
            pixels_over += over as usize;
        }
        let values = 3 * self.width as u64 * self.height as u64;
        Ok(ImageDifference {
            mean: if values == 0 {
                0.0
            } else {
                sum as f64 / values as f64
            },
            max,
            pixels_over,
        })
    }

    /// `self` and `other` side by side, top-aligned, on `background`.
    pub fn beside(&self, other: &Image, gap: u32, background: [u8; 4]) -> Image {
        let width = self.width + gap + other.width;
        let height = self.height.max(other.height);
        let mut out = Image::filled(width, height, background);
        for (image, x0) in [(self, 0), (other, self.width + gap)] {
            let row_bytes = 4 * image.width as usize;
            for y in 0..image.height as usize {
                let src = &image.rgba[y * row_bytes..(y + 1) * row_bytes];
                let start = 4 * (y * width as usize + x0 as usize);
                out.rgba[start..start + row_bytes].copy_from_slice(src);
            }
        }
        out
    }
}
