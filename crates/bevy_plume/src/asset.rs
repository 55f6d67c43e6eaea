//! Effect files as Bevy assets: [`PlumeEffectAsset`] and its loader. The loader compiles the
//! file with Plume's compiler, so an error is reported where the file is (Plume's located
//! diagnostic, file:line:col with a caret) and no broken effect ever reaches the GPU; on a
//! failed hot reload Bevy keeps the last good asset, so the effect keeps running.
//!
//! The files an effect names (textures and maps, meshes, height images, vector fields) are
//! read through the loader's `LoadContext`, from the effect's own asset source, relative to
//! the effect's path: they load from embedded and custom sources alike, and as the loader's
//! dependencies an edit to one reloads the effect. The loader asks the compiler which files
//! it needs (a first compile that reads none), reads them, and compiles with their bytes.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoader, LoadContext};
use bevy::prelude::*;
use bevy::reflect::TypePath;
use plume_compiler::files::{FileSource, Files};
use plume_compiler::graph::{compile_graph_str, CompiledGraph};
use plume_compiler::CompileOptions;

/// A compiled Plume effect file (a single system or a graph of groups and events).
#[derive(Asset, TypePath, Clone, Debug)]
pub struct PlumeEffectAsset {
    /// The asset path it was loaded from (for messages).
    pub path: Arc<str>,
    /// The file's text (compiled again for an instance with its own seed).
    pub source: Arc<str>,
    /// The directory the effect's own files (a texture) are resolved against.
    pub base_dir: Option<Arc<Path>>,
    /// Where those files are read from: the bytes the loader read through Bevy's asset
    /// server; None for an effect compiled from code, whose files are read from disk.
    pub files: Option<Files>,
    /// A Bevy mesh (as OBJ text) that every particle of the top group is drawn as
    /// ([`crate::PlumeEffect::with_mesh`]), whatever the file's look says.
    pub particle_mesh: Option<Arc<[u8]>>,
    /// The compiled effect as written (local space, the file's seed), shared with the render
    /// world (cloning the asset is cheap). Instances in world space or with their own seed
    /// run a variant compiled from `source` once per distinct (seed, space).
    pub graph: Arc<CompiledGraph>,
}

impl PlumeEffectAsset {
    /// Compiles `source` (read from `path`, whose files, a texture, are resolved from
    /// `base_dir`), or returns the located diagnostic as text.
    /// Its files are read from disk.
    pub fn compile(path: &str, source: &str, base_dir: Option<PathBuf>) -> Result<Self, String> {
        Self::compile_from(path, source, base_dir, None)
    }

    /// [`Self::compile`] with the effect's files read from `files` (by their paths resolved
    /// against `base_dir`) instead of from disk.
    fn compile_from(
        path: &str,
        source: &str,
        base_dir: Option<PathBuf>,
        files: Option<Files>,
    ) -> Result<Self, String> {
        let base_dir: Option<Arc<Path>> = base_dir.map(Arc::from);
        let graph = compile_source(
            path,
            source,
            (base_dir.as_deref(), &files),
            Variant::default(),
        )?;
        Ok(Self {
            path: path.into(),
            source: source.into(),
            base_dir,
            files,
            particle_mesh: None,
            graph: Arc::new(graph),
        })
    }

    /// The file compiled again with every particle of its top group drawn as the mesh `obj`
    /// (OBJ text, [`crate::mesh_particles::obj_of`]), or the located diagnostic as text.
    pub fn with_mesh(&self, obj: Vec<u8>) -> Result<Self, String> {
        let mut meshed = Self {
            particle_mesh: Some(obj.into()),
            ..self.clone()
        };
        meshed.graph = Arc::new(meshed.compile_with(Variant::default())?);
        Ok(meshed)
    }

    /// The file compiled again for `variant`, or the located diagnostic as text.
    pub fn compile_with(&self, variant: Variant) -> Result<CompiledGraph, String> {
        let Some(obj) = &self.particle_mesh else {
            let place = (self.base_dir.as_deref(), &self.files);
            return compile_source(&self.path, &self.source, place, variant);
        };
        // The mesh stands as a file of its own beside the effect, which the look names.
        let base_dir = self.base_dir.as_deref().unwrap_or(Path::new(""));
        let files = Some(Files(Arc::new(WithMesh {
            path: base_dir.join(BEVY_MESH),
            obj: obj.clone(),
            others: self.files.clone(),
        })));
        let options = options_for((Some(base_dir), &files), variant);
        let render = |e: plume_compiler::CompileError| e.render(&self.path, &self.source);
        let mut effect = plume_compiler::parse_with(&self.source, &options).map_err(render)?;
        effect.render.mesh = Some(plume_compiler::particle_mesh::ParticleMesh {
            file: BEVY_MESH.into(),
        });
        plume_compiler::graph::compile_graph(&effect, &self.source).map_err(render)
    }

    /// The step of the top-level group, in seconds.
    pub fn dt(&self) -> f64 {
        self.graph.groups[0].effect.ir.dt
    }
}

/// How an instance needs its file compiled; the default is the file as written.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Variant {
    /// Replaces the file's seed.
    pub seed: Option<u32>,
    /// Placed in the world at run time (world space).
    pub placed: bool,
    /// Takes bursts from code.
    pub bursts: bool,
    /// Reads its params at run time.
    pub live_params: bool,
}

/// Compiles an effect file's text, its diagnostic rendered against `path` when it fails.
fn compile_source(
    path: &str,
    source: &str,
    place: (Option<&Path>, &Option<Files>),
    variant: Variant,
) -> Result<CompiledGraph, String> {
    let options = options_for(place, variant);
    compile_graph_str(source, &options).map_err(|e| e.render(path, source))
}

/// The name a Bevy mesh particle's mesh stands under beside the effect.
const BEVY_MESH: &str = "(bevy mesh).obj";

/// The options that compile an effect for `variant`, its files resolved against `base_dir`
/// and read from `files` (disk when None).
fn options_for(
    (base_dir, files): (Option<&Path>, &Option<Files>),
    variant: Variant,
) -> CompileOptions {
    CompileOptions {
        base_dir: base_dir.map(Path::to_path_buf),
        files: files.clone(),
        seed: variant.seed,
        placed: variant.placed,
        bursts: variant.bursts,
        live_params: variant.live_params,
        // A lit look reads Bevy's shadow maps where a light casts them.
        receive_shadows: true,
        ..Default::default()
    }
}

/// A Bevy mesh at `path` (OBJ text), and the effect's other files.
struct WithMesh {
    path: PathBuf,
    obj: Arc<[u8]>,
    others: Option<Files>,
}

impl FileSource for WithMesh {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        match (path == self.path, &self.others) {
            (true, _) => Ok(self.obj.to_vec()),
            (false, Some(others)) => others.0.read(path),
            (false, None) => plume_compiler::files::Disk.read(path),
        }
    }
}

/// Why an effect file did not load. The compile error carries Plume's whole diagnostic.
#[derive(Debug, thiserror::Error)]
pub enum PlumeLoadError {
    /// The file could not be read.
    #[error("could not read {path}: {source}")]
    Read {
        /// The asset path.
        path: String,
        /// The reader's error.
        source: std::io::Error,
    },
    /// The file is not UTF-8.
    #[error("{path} is not UTF-8 text")]
    NotText {
        /// The asset path.
        path: String,
    },
    /// The compiler refused the file; the text is its located diagnostic.
    #[error("{0}")]
    Compile(String),
    /// The files the effect names kept naming more files, past the rounds the loader reads.
    #[error("{path}: its files name more files after {rounds} rounds of reading them")]
    FileRounds {
        /// The asset path.
        path: String,
        /// The rounds read.
        rounds: usize,
    },
}

/// Loads `*.plume.ron` and `*.plume` files (and any file loaded with the type
/// `PlumeEffectAsset`, whatever its extension, such as the examples' `effects/*.ron`), with
/// the files they name read through the asset server.
#[derive(Default, TypePath)]
pub struct PlumeEffectLoader;

impl AssetLoader for PlumeEffectLoader {
    type Asset = PlumeEffectAsset;
    type Settings = ();
    type Error = PlumeLoadError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<Self::Asset, Self::Error> {
        let asset_path = load_context.path().path().to_path_buf();
        let path = asset_path.display().to_string();
        let mut bytes = Vec::new();
        reader
            .read_to_end(&mut bytes)
            .await
            .map_err(|source| PlumeLoadError::Read {
                path: path.clone(),
                source,
            })?;
        let source =
            String::from_utf8(bytes).map_err(|_| PlumeLoadError::NotText { path: path.clone() })?;
        // The compiler resolves a file against the effect's directory in its source; the
        // loader reads it back as the asset path the name gives relative to the effect.
        let base_dir = asset_path.parent().unwrap_or(Path::new("")).to_path_buf();
        // Compiled with the files read so far, each file it asks for and was not given is
        // read through the asset server, and it is compiled again: until it asks for nothing
        // new (a glTF names its buffers, read only once the glTF itself is).
        let mut read = HashMap::new();
        for _ in 0..MAX_FILE_ROUNDS {
            let files = Arc::new(Loaded {
                read: std::mem::take(&mut read),
                asked: Mutex::default(),
            });
            let compiled = PlumeEffectAsset::compile_from(
                &path,
                &source,
                Some(base_dir.clone()),
                Some(Files(files.clone())),
            );
            let wanted = files.asked();
            if wanted.is_empty() {
                // Bevy's asset server logs the error, the located diagnostic whole, and keeps
                // the last good version of the asset (on a hot reload) in use.
                return compiled.map_err(PlumeLoadError::Compile);
            }
            // The asset keeps its files (its variants compile from them): the bytes are
            // copied only where another round is needed.
            read = files.read.clone();
            for wanted in wanted {
                let name = wanted.strip_prefix(&base_dir).unwrap_or(&wanted);
                let bytes = match load_context
                    .path()
                    .resolve_embed_str(&name.to_string_lossy())
                {
                    Ok(file) => match load_context.read_asset_bytes(&file).await {
                        Ok(bytes) => Ok(bytes),
                        Err(e) => Err(format!("{file}: {e}")),
                    },
                    Err(e) => Err(e.to_string()),
                };
                read.insert(wanted, bytes);
            }
        }
        Err(PlumeLoadError::FileRounds {
            path,
            rounds: MAX_FILE_ROUNDS,
        })
    }

    fn extensions(&self) -> &[&str] {
        &["plume.ron", "plume"]
    }
}

/// The most rounds of files the loader reads for one effect (the files it names, then the
/// files those name, ...).
const MAX_FILE_ROUNDS: usize = 8;

/// The files the loader read through the asset server so far, by the paths the compiler asks
/// for (or why one could not be read), and those it asked for that are not among them yet.
struct Loaded {
    read: HashMap<PathBuf, Result<Vec<u8>, String>>,
    asked: Mutex<Vec<PathBuf>>,
}

impl Loaded {
    /// The files asked for and not read yet, each once.
    fn asked(&self) -> Vec<PathBuf> {
        let mut paths = self.asked.lock().unwrap_or_else(|p| p.into_inner()).clone();
        paths.sort();
        paths.dedup();
        paths
    }
}

impl FileSource for Loaded {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        match self.read.get(path) {
            Some(Ok(bytes)) => Ok(bytes.clone()),
            Some(Err(why)) => Err(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                why.clone(),
            )),
            None => {
                let mut asked = self.asked.lock().unwrap_or_else(|p| p.into_inner());
                asked.push(path.to_path_buf());
                Err(std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "not read yet",
                ))
            }
        }
    }
}
