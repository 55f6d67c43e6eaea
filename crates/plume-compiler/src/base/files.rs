//! Where the compiler reads the files an effect names (textures and maps, meshes, height
//! images, vector fields): from disk, or from a host's [`FileSource`] given in
//! `CompileOptions::files` (the Bevy plugin's, which reads them through Bevy's asset server,
//! so that they load from any asset source and an edit reloads the effect). The source is set
//! for the length of one compile on the compiling thread ([`with_source`]); every reader asks
//! `read` for bytes, so no feature opens a file itself.

use std::cell::RefCell;
use std::path::Path;
use std::sync::Arc;

/// A host's files, by the path the compiler resolved (the effect's `base_dir` joined with the
/// name the file gives).
///
/// ```
/// use std::path::Path;
/// use std::sync::Arc;
/// use plume_compiler::files::{FileSource, Files};
///
/// /// One 2x2 red PNG, wherever it is looked for.
/// struct Red;
/// impl FileSource for Red {
///     fn read(&self, _path: &Path) -> std::io::Result<Vec<u8>> {
///         let image = image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 0, 0, 255]));
///         let mut png = std::io::Cursor::new(Vec::new());
///         image.write_to(&mut png, image::ImageFormat::Png).map_err(std::io::Error::other)?;
///         Ok(png.into_inner())
///     }
/// }
///
/// let source = r#"Effect(name: "dots", capacity: 4,
///     emitters: [Emitter(burst: 4, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
///     render: Render(texture: Some(Texture(file: "not/on/disk.png"))))"#;
/// let options = plume_compiler::CompileOptions {
///     files: Some(Files(Arc::new(Red))),
///     ..Default::default()
/// };
/// let effect = plume_compiler::compile_str(source, &options).unwrap();
/// let texture = effect.ir.render.texture.as_ref().unwrap();
/// assert_eq!((texture.width, texture.height), (2, 2));
/// // From the disk, the file is not there: a located error.
/// assert!(plume_compiler::compile_str(source, &Default::default()).is_err());
/// ```
pub trait FileSource: Send + Sync {
    /// The bytes of the file at `path`.
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>>;
}

/// A [`FileSource`] shared by the options and effects that carry it (compared by identity).
#[derive(Clone)]
pub struct Files(pub Arc<dyn FileSource>);

impl std::fmt::Debug for Files {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Files(a host's source)")
    }
}

impl PartialEq for Files {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The disk as a [`FileSource`]: for a host's source that serves some files itself and
/// leaves the rest where they lie.
pub struct Disk;

impl FileSource for Disk {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        std::fs::read(path)
    }
}

thread_local! {
    static CURRENT: RefCell<Option<Files>> = const { RefCell::new(None) };
}

/// Runs `f` with `files` as the source `read` reads from (disk when None), then puts back
/// the one before.
pub fn with_source<R>(files: Option<Files>, f: impl FnOnce() -> R) -> R {
    let before = CURRENT.with(|c| c.replace(files));
    let result = f();
    CURRENT.with(|c| *c.borrow_mut() = before);
    result
}

/// The bytes of the file at `path`, from the current source, at most `most` of them: a larger
/// file is refused (with its size) before it is read from disk.
pub(crate) fn read(path: &Path, most: u64) -> Result<Vec<u8>, ReadError> {
    let bytes = match CURRENT.with(|c| c.borrow().clone()) {
        Some(files) => files.0.read(path).map_err(ReadError::Open)?,
        None => {
            let size = std::fs::metadata(path).map_err(ReadError::Open)?.len();
            if size > most {
                return Err(ReadError::TooLarge(size));
            }
            std::fs::read(path).map_err(ReadError::Read)?
        }
    };
    match bytes.len() as u64 {
        size if size > most => Err(ReadError::TooLarge(size)),
        _ => Ok(bytes),
    }
}

/// Whether files are read from disk (no host source), where the compiler may keep caches
/// beside them.
pub(crate) fn on_disk() -> bool {
    CURRENT.with(|c| c.borrow().is_none())
}

/// Why a file could not be read.
#[derive(Debug)]
pub(crate) enum ReadError {
    /// It could not be found or opened.
    Open(std::io::Error),
    /// It was opened but not read.
    Read(std::io::Error),
    /// It has more bytes than its reader takes.
    TooLarge(u64),
}

#[cfg(test)]
mod tests {
    use super::*;

    struct One;

    impl FileSource for One {
        fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
            match path == Path::new("a/b.txt") {
                true => Ok(b"hello".to_vec()),
                false => Err(std::io::ErrorKind::NotFound.into()),
            }
        }
    }

    #[test]
    fn a_hosts_source_serves_reads_for_the_length_of_the_call() {
        let files = Files(Arc::new(One));
        let inside = with_source(Some(files), || {
            assert!(!on_disk());
            read(Path::new("a/b.txt"), 5).unwrap()
        });
        assert_eq!(inside, b"hello");
        assert!(on_disk());
        let files = Files(Arc::new(One));
        let too_large = with_source(Some(files), || read(Path::new("a/b.txt"), 4));
        assert!(matches!(too_large, Err(ReadError::TooLarge(5))));
        assert!(matches!(
            read(Path::new("no/such/file.plume"), 10),
            Err(ReadError::Open(_))
        ));
    }
}
