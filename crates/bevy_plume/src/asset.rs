//! Effect files as Bevy assets: [`PlumeEffectAsset`] and its loader. The loader compiles the
//! file with Plume's compiler, so an error is reported where the file is (Plume's located
//! diagnostic, file:line:col with a caret) and no broken effect ever reaches the GPU; on a
//! failed hot reload Bevy keeps the last good asset, so the effect keeps running.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use bevy::asset::io::Reader;
use bevy::asset::{AssetLoader, LoadContext};
use bevy::prelude::*;
use bevy::reflect::TypePath;
use plume_compiler::graph::{compile_graph_str, CompiledGraph};
use plume_compiler::CompileOptions;

/// A compiled Plume effect file (a single system or a graph of groups and events).
#[derive(Asset, TypePath, Clone, Debug)]
pub struct PlumeEffectAsset {
    /// The asset path it was loaded from (for messages).
    pub path: Arc<str>,
    /// The file's text (compiled again for an instance with its own seed).
    pub source: Arc<str>,
    /// The directory the effect's own files (a texture) are read from.
    pub base_dir: Option<Arc<Path>>,
    /// The compiled effect as written (local space, the file's seed), shared with the render
    /// world (cloning the asset is cheap). Instances in world space or with their own seed
    /// run a variant compiled from `source` once per distinct (seed, space).
    pub graph: Arc<CompiledGraph>,
}

impl PlumeEffectAsset {
    /// Compiles `source` (read from `path`, whose files, a texture, are resolved from
    /// `base_dir`), or returns the located diagnostic as text.
    pub fn compile(path: &str, source: &str, base_dir: Option<PathBuf>) -> Result<Self, String> {
        let base_dir: Option<Arc<Path>> = base_dir.map(Arc::from);
        let graph = compile_source(path, source, base_dir.as_deref(), Variant::default())?;
        Ok(Self {
            path: path.into(),
            source: source.into(),
            base_dir,
            graph: Arc::new(graph),
        })
    }

    /// The file compiled again for `variant`, or the located diagnostic as text.
    pub fn compile_with(&self, variant: Variant) -> Result<CompiledGraph, String> {
        compile_source(&self.path, &self.source, self.base_dir.as_deref(), variant)
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
    base_dir: Option<&Path>,
    variant: Variant,
) -> Result<CompiledGraph, String> {
    let options = CompileOptions {
        base_dir: base_dir.map(Path::to_path_buf),
        seed: variant.seed,
        placed: variant.placed,
        bursts: variant.bursts,
        live_params: variant.live_params,
        ..Default::default()
    };
    compile_graph_str(source, &options).map_err(|e| e.render(path, source))
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
}

/// Loads `*.plume.ron` and `*.plume` files (and any file loaded with the type
/// `PlumeEffectAsset`, whatever its extension, such as the examples' `effects/*.ron`).
#[derive(Default, TypePath)]
pub struct PlumeEffectLoader {
    /// The directory asset paths are relative to, for an effect's own files (a texture).
    pub(crate) root: Option<PathBuf>,
}

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
        let base_dir = self
            .root
            .as_deref()
            .map(|root| root.join(asset_path.parent().unwrap_or(Path::new(""))));
        // Bevy's asset server logs the error, the located diagnostic whole, and keeps the last
        // good version of the asset (on a hot reload) in use.
        PlumeEffectAsset::compile(&path, &source, base_dir).map_err(PlumeLoadError::Compile)
    }

    fn extensions(&self) -> &[&str] {
        &["plume.ron", "plume"]
    }
}
