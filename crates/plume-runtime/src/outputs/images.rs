//! Encoding rendered frames: a PNG of one frame or of a contact sheet, or an animated GIF.

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, ImageEncoder, RgbaImage};

use crate::error::RuntimeError;

/// One RGBA8 frame.
#[derive(Clone, Debug)]
pub struct Frame8 {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Rows of RGBA8 pixels, top first.
    pub pixels: Vec<u8>,
}

fn to_image(f: &Frame8) -> Result<RgbaImage, RuntimeError> {
    RgbaImage::from_raw(f.width, f.height, f.pixels.clone())
        .ok_or_else(|| RuntimeError::Output("frame has the wrong number of pixels".into()))
}

/// Encodes one frame as PNG.
pub fn png(frame: &Frame8) -> Result<Vec<u8>, RuntimeError> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(
            &frame.pixels,
            frame.width,
            frame.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| RuntimeError::Output(format!("PNG encoding failed: {e}")))?;
    Ok(out)
}

/// Tiles frames left to right, top to bottom, in ceil(sqrt(n)) columns.
pub fn contact_sheet(frames: &[Frame8]) -> Result<Frame8, RuntimeError> {
    let first = frames
        .first()
        .ok_or_else(|| RuntimeError::Output("no frames to put on a sheet".into()))?;
    let cols = (frames.len() as f64).sqrt().ceil() as u32;
    let rows = (frames.len() as u32).div_ceil(cols);
    let (w, h) = (first.width, first.height);
    let mut sheet = RgbaImage::new(w * cols, h * rows);
    for (i, f) in frames.iter().enumerate() {
        let img = to_image(f)?;
        let (x, y) = ((i as u32 % cols) * w, (i as u32 / cols) * h);
        image::imageops::replace(&mut sheet, &img, i64::from(x), i64::from(y));
    }
    Ok(Frame8 {
        width: sheet.width(),
        height: sheet.height(),
        pixels: sheet.into_raw(),
    })
}

/// Encodes frames as a looping GIF, each shown for `delay_ms` milliseconds.
pub fn gif(frames: &[Frame8], delay_ms: u32) -> Result<Vec<u8>, RuntimeError> {
    let mut out = Vec::new();
    {
        let mut encoder = GifEncoder::new_with_speed(&mut out, 10);
        encoder
            .set_repeat(Repeat::Infinite)
            .map_err(|e| RuntimeError::Output(format!("GIF encoding failed: {e}")))?;
        for f in frames {
            let frame =
                Frame::from_parts(to_image(f)?, 0, 0, Delay::from_numer_denom_ms(delay_ms, 1));
            encoder
                .encode_frame(frame)
                .map_err(|e| RuntimeError::Output(format!("GIF encoding failed: {e}")))?;
        }
    }
    Ok(out)
}
