//! An RGBA8 image in memory: PNG encoding and side-by-side layouts of several renders.

use super::RenderError;

/// Rows top to bottom, 4 bytes (R, G, B, A) per pixel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl Image {
    /// An image of one colour.
    pub fn filled(width: u32, height: u32, rgba: [u8; 4]) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            rgba: rgba.iter().copied().cycle().take(4 * n).collect(),
        }
    }

    /// The pixel at column `x`, row `y` (from the top).
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 4] {
        let i = 4 * (y as usize * self.width as usize + x as usize);
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }

    /// Images laid out left to right, top to bottom, `columns` per row, each cell as large as
    /// the largest image, on `background`.
    pub fn grid(images: &[Image], columns: usize, background: [u8; 4]) -> Image {
        let columns = columns.clamp(1, images.len().max(1));
        let rows = images.len().div_ceil(columns).max(1);
        let cw = images.iter().map(|i| i.width).max().unwrap_or(1);
        let ch = images.iter().map(|i| i.height).max().unwrap_or(1);
        let mut out = Image::filled(cw * columns as u32, ch * rows as u32, background);
        for (k, img) in images.iter().enumerate() {
            let (x0, y0) = ((k % columns) as u32 * cw, (k / columns) as u32 * ch);
            for y in 0..img.height {
                let src = 4 * (y * img.width) as usize;
                let dst = 4 * ((y0 + y) as usize * out.width as usize + x0 as usize);
                let len = 4 * img.width as usize;
                out.rgba[dst..dst + len].copy_from_slice(&img.rgba[src..src + len]);
            }
        }
        out
    }

    /// The image as a PNG file (8-bit RGBA).
    #[cfg(feature = "render")]
    pub fn png(&self) -> Result<Vec<u8>, RenderError> {
        let mut bytes = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut bytes, self.width, self.height);
            enc.set_color(png::ColorType::Rgba);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc
                .write_header()
                .map_err(|e| RenderError::Png(e.to_string()))?;
            w.write_image_data(&self.rgba)
                .map_err(|e| RenderError::Png(e.to_string()))?;
        }
        Ok(bytes)
    }

    /// Without the `render` feature there is no PNG encoder.
    #[cfg(not(feature = "render"))]
    pub fn png(&self) -> Result<Vec<u8>, RenderError> {
        Err(RenderError::NotBuiltIn)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_places_each_image_in_its_cell() {
        let a = Image::filled(2, 1, [1, 2, 3, 255]);
        let b = Image::filled(1, 2, [9, 9, 9, 255]);
        let g = Image::grid(&[a, b], 2, [0, 0, 0, 255]);
        assert_eq!((g.width, g.height), (4, 2));
        assert_eq!(g.pixel(1, 0), [1, 2, 3, 255]);
        assert_eq!(g.pixel(1, 1), [0, 0, 0, 255]);
        assert_eq!(g.pixel(2, 1), [9, 9, 9, 255]);
        assert_eq!(g.pixel(3, 0), [0, 0, 0, 255]);
    }

    #[cfg(feature = "render")]
    #[test]
    fn png_has_the_signature_and_size() {
        let png = Image::filled(3, 2, [10, 20, 30, 255]).png().unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        // IHDR: width and height big-endian at bytes 16..24
        assert_eq!(&png[16..24], &[0, 0, 0, 3, 0, 0, 0, 2]);
    }
}
