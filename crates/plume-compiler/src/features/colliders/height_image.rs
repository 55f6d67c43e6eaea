//! Height fields from images: `HeightField(image: "terrain.png", height: (0.0, 3.0), ..)`
//! reads an 8- or 16-bit greyscale PNG into the field's grid of heights, black at the first
//! height and white at the second, linear between. The image's top row is the first z sample
//! (min z) and its left column the first x sample (min x), as the rows of `heights` are. The
//! heights are read once, at compile time, so the GPU and the f64 reference collide with the
//! very same grid ([`super::height_field`] does the rest).

use std::path::{Path, PathBuf};

use super::height_field::MAX_SAMPLES;
use super::{collider_path, Collider};
use crate::base::check::Checker;

/// Reads `file` (relative to `base_dir`, the effect file's directory, when given) into rows
/// of heights from `black` to `white`; an error says what is wrong with the file, for the
/// collider's `image` field.
pub(crate) fn read(
    file: &str,
    base_dir: Option<&Path>,
    (black, white): (f64, f64),
) -> Result<Vec<Vec<f64>>, String> {
    let path = base_dir.map_or_else(|| PathBuf::from(file), |dir| dir.join(file));
    let shown = path.display();
    use crate::base::files::ReadError;
    let most = crate::features::looks::texture::MAX_FILE_BYTES;
    let bytes = crate::base::files::read(&path, most).map_err(|e| match e {
        ReadError::Open(e) => format!("cannot open height image `{shown}`: {e}"),
        ReadError::Read(e) => format!("cannot read height image `{shown}`: {e}"),
        ReadError::TooLarge(size) => {
            format!("height image `{shown}` is {size} bytes, more than the {most} read")
        }
    })?;
    let open = || {
        image::ImageReader::new(std::io::Cursor::new(bytes.as_slice()))
            .with_guessed_format()
            .map_err(|e| format!("cannot open height image `{shown}`: {e}"))
    };
    // The size first, from the header: a huge image is refused before it is decoded.
    let (width, height) = open()?
        .into_dimensions()
        .map_err(|e| format!("cannot read height image `{shown}`: {e}"))?;
    let samples = u64::from(width) * u64::from(height);
    if samples > MAX_SAMPLES as u64 {
        return Err(format!(
            "height image `{shown}` is {width} x {height} = {samples} samples, more than the {MAX_SAMPLES} a height field may have: scale it down"
        ));
    }
    if width < 2 || height < 2 {
        return Err(format!(
            "height image `{shown}` is {width} x {height}: a height field needs at least 2 x 2 samples"
        ));
    }
    let decoded = open()?
        .decode()
        .map_err(|e| format!("cannot decode height image `{shown}`: {e}"))?;
    let (levels, top): (Vec<f64>, f64) = match &decoded {
        image::DynamicImage::ImageLuma8(grey) => {
            (grey.as_raw().iter().map(|&v| f64::from(v)).collect(), 255.0)
        }
        image::DynamicImage::ImageLuma16(grey) => (
            grey.as_raw().iter().map(|&v| f64::from(v)).collect(),
            65535.0,
        ),
        other => {
            return Err(format!(
                "height image `{shown}` is {:?}: a height field reads 8- or 16-bit greyscale without alpha (save it as grey)",
                other.color()
            ))
        }
    };
    Ok(levels
        .chunks_exact(width as usize)
        .map(|row| {
            row.iter()
                .map(|&v| black + (white - black) * (v / top))
                .collect()
        })
        .collect())
}

/// Reads every height field's `image` into its `heights` (files relative to `base_dir`),
/// recording what is wrong, located at the field, in `c`: an unreadable image, `image` and
/// `heights` both given, or `image` and `height` without each other.
pub(crate) fn read_height_images(
    collide: &mut [Collider],
    base_dir: Option<&Path>,
    c: &mut Checker,
) {
    for (i, collider) in collide.iter_mut().enumerate() {
        let path = collider_path(i, collider);
        let Collider::HeightField(super::height_field::HeightField {
            heights,
            image,
            height,
            ..
        }) = collider
        else {
            continue;
        };
        match (image.as_deref(), *height) {
            (None, None) => {}
            (None, Some(_)) => c.error(
                &path.field("height"),
                "`height` gives the heights of black and white in an `image`: give the image too, or drop it",
            ),
            (Some(_), None) => c.error(
                &path.field("image"),
                "an image needs `height: (black, white)`, the heights (m) its darkest and lightest grey stand for",
            ),
            (Some(_), Some(_)) if !heights.is_empty() => c.error(
                &path.field("image"),
                "give the heights either as `heights` or as an `image`, not both",
            ),
            (Some(file), Some((black, white))) => {
                if c.finite(&path.field("height").component(0, "black"), black)
                    & c.finite(&path.field("height").component(1, "white"), white)
                {
                    match read(file, base_dir, (black, white)) {
                        Ok(rows) => *heights = rows,
                        Err(message) => c.error(&path.field("image"), message),
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, image: image::DynamicImage) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("plume-height-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        image.save(&path).unwrap();
        path
    }

    #[test]
    fn grey_pixels_become_heights_row_by_row() {
        let mut grey = image::GrayImage::new(3, 2);
        for (x, y, p) in grey.enumerate_pixels_mut() {
            p.0 = [(x * 100 + y * 10) as u8];
        }
        let path = write("ramp8.png", grey.into());
        let rows = read(path.to_str().unwrap(), None, (1.0, 1.0 + 255.0)).unwrap();
        assert_eq!(
            rows,
            vec![vec![1.0, 101.0, 201.0], vec![11.0, 111.0, 211.0]]
        );
        let mut deep = image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(2, 2);
        deep.put_pixel(1, 1, image::Luma([65535]));
        let path = write("deep16.png", image::DynamicImage::ImageLuma16(deep));
        let rows = read(path.to_str().unwrap(), None, (-2.0, 2.0)).unwrap();
        assert_eq!(rows, vec![vec![-2.0, -2.0], vec![-2.0, 2.0]]);
    }

    #[test]
    fn bad_images_are_refused_with_why() {
        let colour = write("rgb.png", image::RgbImage::new(4, 4).into());
        let error = read(colour.to_str().unwrap(), None, (0.0, 1.0)).unwrap_err();
        assert!(
            error.contains("Rgb8") && error.contains("greyscale"),
            "{error}"
        );
        let thin = write("thin.png", image::GrayImage::new(1, 5).into());
        let error = read(thin.to_str().unwrap(), None, (0.0, 1.0)).unwrap_err();
        assert!(
            error.contains("1 x 5") && error.contains("2 x 2"),
            "{error}"
        );
        let huge = write("huge.png", image::GrayImage::new(1100, 1000).into());
        let error = read(huge.to_str().unwrap(), None, (0.0, 1.0)).unwrap_err();
        assert!(
            error.contains("1100000 samples") && error.contains("1048576"),
            "{error}"
        );
        let error = read("no/such/terrain.png", None, (0.0, 1.0)).unwrap_err();
        assert!(
            error.contains("cannot open height image `no/such/terrain.png`"),
            "{error}"
        );
    }
}
