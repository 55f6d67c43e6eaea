//! The single-group driver: parse (with overrides), then check, lower, run the passes, emit
//! the WGSL modules and validate them with naga. Effect graphs call [`compile_group`] once
//! per group (`crate::graph`), handing each its event links ([`GroupLinks`]).

use crate::base::diagnostics::{self, Diagnostic, Diagnostics, Severity};
use crate::base::locate::SourceMap;
use crate::base::naga_check;
use crate::base::path::ValuePath;
use crate::features::events::{EventInputIr, EventIr};
use crate::features::looks::{particle_mesh, texture};
use crate::ir::EffectIr;
use crate::stages::passes::layout::Layout;
use crate::stages::schema::{EffectSpec, Emitter, Integrator};
use crate::stages::{lower, passes, validate, wgsl};

/// Overrides applied on top of the effect file (as `plume run --dt` etc. do), and where the
/// files it names are.
///
/// ```
/// let source = r#"Effect(name: "flakes", capacity: 10,
///     emitters: [Emitter(burst: 10, shape: Point((0.0, 0.0, 0.0)), velocity: Constant((0.0, 0.0, 0.0)))],
///     render: Render(texture: Some(Texture(file: "textures/snowflake.png"))))"#;
/// // The texture is named relative to the effect file, which lies in effects/.
/// let options = plume_compiler::CompileOptions {
///     base_dir: Some("../../effects".into()),
///     ..Default::default()
/// };
/// let effect = plume_compiler::compile_str(source, &options).unwrap();
/// let texture = effect.ir.render.texture.as_ref().unwrap();
/// assert_eq!((texture.width, texture.height, texture.frames()), (64, 64, 1));
/// // Looked for elsewhere, it is not found: an error located at the file's name.
/// let error = plume_compiler::compile_str(source, &Default::default()).unwrap_err();
/// assert!(error.render("flakes.ron", source).contains("render.texture.file: cannot open texture"));
/// ```
#[derive(Clone, Debug, Default)]
pub struct CompileOptions {
    /// Replaces the file's `dt`.
    pub dt: Option<f64>,
    /// Replaces the file's `seed`.
    pub seed: Option<u32>,
    /// Replaces the file's `integrator`.
    pub integrator: Option<Integrator>,
    /// Replaces the file's `substeps`.
    pub substeps: Option<u32>,
    /// Replaces the file's `sort` (as `plume run --order draw` does).
    pub sort: Option<bool>,
    /// Replaces the file's `state`.
    pub state: Option<crate::stages::schema::State>,
    /// The directory the effect's files (`render.texture.file`) are relative to: the effect
    /// file's directory. None: the current directory.
    pub base_dir: Option<std::path::PathBuf>,
    /// Compiles the effect to be placed in a host's world by a transform set at run time
    /// (world space: emitters spawn through it, particles stay where they were emitted;
    /// `features::placement`). The effect is then stateful.
    pub placed: bool,
    /// Compiles the effect to take bursts fired from code at run time (`features::bursts`):
    /// its step parameters carry up to `bursts::SLOTS` per step. The effect is then stateful.
    pub bursts: bool,
    /// Compiles `params` to be read at run time from the step parameters, so that a host can
    /// change them without recompiling (`Effect::set_param`); otherwise they are folded as
    /// constants. The compile-time analyses (stiffness, the integrator `Auto` picks) see the
    /// file's values.
    pub live_params: bool,
    /// Compiles the effect to be stepped, not drawn (`plume run`, `plume bench` without
    /// drawing): a sprite texture that cannot be read is then no error here. The effect keeps
    /// its flipbook's frames (the step may need its particles' ages), with a white stand-in of
    /// one texel a frame, and any draw of it is refused with the reason, naming the file and
    /// the field (`TextureIr::missing`).
    pub step_only: bool,
    /// Compiles a lit look to read a shadow map a host gives at run time
    /// (`EffectRenderer::set_shadow_map`) even where no light of the file casts one: the Bevy
    /// plugin sets it, so that Bevy's shadows fall on lit particles. Without it, and without
    /// a `shadow: true` light, the draw holds no shadow lookup (it costs a lit draw a few
    /// percent: docs/performance.md, "Received shadows").
    pub receive_shadows: bool,
    /// Where the files the effect names are read from: a host's source (the Bevy plugin's
    /// asset server), each file by its path resolved against `base_dir`. None: the disk.
    pub files: Option<crate::base::files::Files>,
    /// The camera a pixel budget (`accuracy: (pixels: ...)`) is measured through: a host's, or
    /// the preview's, instead of the file's `camera`, so that the integration is chosen for
    /// the view the effect is seen in. None: the file's camera.
    pub accuracy_camera: Option<crate::stages::schema::Camera>,
}

/// A compiled effect: the IR after the passes, its layout, the WGSL and any warnings.
#[derive(Clone, Debug)]
pub struct CompiledEffect {
    /// The IR after all passes (integrator resolved).
    pub ir: EffectIr,
    /// Particle struct and bindings.
    pub layout: Layout,
    /// The naga-validated WGSL compute module.
    pub wgsl: String,
    /// The naga-validated WGSL draw module (vertex and fragment shaders) for one particle
    /// buffer: see [`wgsl::draw`]. The runtime emits another shape when it needs one.
    pub draw_wgsl: String,
    /// The naga-validated WGSL trail draw module (`render.trail`; see [`wgsl::trail`]), for
    /// one particle buffer; None for an effect without trails.
    pub trail_wgsl: Option<String>,
    /// The naga-validated WGSL module of the flock's grid search (`Flock(neighbors: Grid)`;
    /// see `emit_search_module`); None for any other effect.
    pub flock_search_wgsl: Option<String>,
    /// Warnings from the stability analysis and other checks, located in the source.
    pub warnings: Diagnostics,
}

/// Why compilation failed.
#[derive(Debug, thiserror::Error)]
pub enum CompileError {
    /// The effect has errors: syntax, unknown fields, or invalid values.
    #[error("{0}")]
    Invalid(Diagnostics),
    /// The compiler emitted WGSL that naga rejects: a bug in Plume, never the user's fault.
    #[error(transparent)]
    Internal(#[from] naga_check::NagaRejection),
}

impl CompileError {
    /// Renders the error for a terminal: rustc-style diagnostics, or the internal error text.
    pub fn render(&self, file_name: &str, source: &str) -> String {
        match self {
            CompileError::Invalid(d) => d.render(file_name, source),
            CompileError::Internal(e) => format!("{file_name}: {e}\n"),
        }
    }
}

/// Parses RON text into the effect schema, with syntax errors located.
pub fn parse(source: &str) -> Result<EffectSpec, Diagnostics> {
    ron::Options::default()
        .from_str::<EffectSpec>(source)
        .map_err(|e| {
            let start = diagnostics::Pos {
                line: e.span.start.line.max(1),
                col: e.span.start.col.max(1),
            };
            let end = diagnostics::Pos {
                line: e.span.end.line.max(1),
                col: e.span.end.col.max(1),
            };
            Diagnostics {
                items: vec![Diagnostic {
                    severity: Severity::Error,
                    path: String::new(),
                    message: e.code.to_string(),
                    span: Some(diagnostics::Span { start, end }),
                }],
            }
        })
}

/// Compiles effect source text: parse, check, lower, run the passes, emit and validate WGSL.
pub fn compile_str(source: &str, options: &CompileOptions) -> Result<CompiledEffect, CompileError> {
    let effect = parse_with(source, options)?;
    compile_effect(&effect, source)
}

/// Parses `source` and applies `options`' overrides (to every group of a graph).
pub fn parse_with(source: &str, options: &CompileOptions) -> Result<EffectSpec, CompileError> {
    let mut effect = parse(source).map_err(CompileError::Invalid)?;
    if let Some(dt) = options.dt {
        effect.dt = dt;
    }
    if let Some(seed) = options.seed {
        effect.seed = seed;
    }
    if let Some(i) = options.integrator {
        effect.integrator = i;
    }
    if let Some(s) = options.substeps {
        effect.substeps = s;
    }
    if let Some(s) = options.sort {
        effect.sort = s;
    }
    if let Some(s) = options.state {
        effect.state = s;
    }
    effect.base_dir.clone_from(&options.base_dir);
    effect.files.clone_from(&options.files);
    effect.receive_shadows = options.receive_shadows;
    effect.placed = options.placed;
    effect.bursts = options.bursts;
    effect.live_params = options.live_params;
    effect.step_only = options.step_only;
    effect.accuracy_camera = options.accuracy_camera;
    for group in &mut effect.groups {
        if let Some(i) = options.integrator {
            group.integrator = i;
        }
        if let Some(s) = options.substeps {
            group.substeps = s;
        }
        if let Some(s) = options.sort {
            group.sort = s;
        }
        if let Some(s) = options.state {
            group.state = s;
        }
    }
    Ok(effect)
}

/// Compiles an already-parsed effect of one group; `source` (may be empty) is used only to
/// locate diagnostics. An effect with `groups` or `events` is a graph: compile it with
/// [`crate::graph::compile_graph`].
pub fn compile_effect(effect: &EffectSpec, source: &str) -> Result<CompiledEffect, CompileError> {
    crate::base::files::with_source(effect.files.clone(), || compile_one(effect, source))
}

/// [`compile_effect`] with the effect's files being read from its source.
fn compile_one(effect: &EffectSpec, source: &str) -> Result<CompiledEffect, CompileError> {
    let map = SourceMap::build(source);
    let locate = |items: Vec<(Diagnostic, String)>| locate_items(&map, source, items);
    if let Some(path) = graph_field(effect) {
        return Err(CompileError::Invalid(locate(vec![(
            Diagnostic::error(
                path.display,
                "this effect has groups or events: it runs as a graph (plume_compiler::graph::compile_graph); this entry point compiles a single group",
            ),
            path.lookup,
        )])));
    }
    compile_group(effect, &GroupLinks::default(), "", &locate)
}

/// Gives each diagnostic the span of its lookup path in `source`.
pub(crate) fn locate_items(
    map: &SourceMap,
    source: &str,
    items: Vec<(Diagnostic, String)>,
) -> Diagnostics {
    Diagnostics {
        items: items
            .into_iter()
            .map(|(mut d, lookup)| {
                d.span = match lookup.split_once('@') {
                    // `path@start..end`: characters of an expression string (Checker::error_in_string).
                    Some((path, range)) => range
                        .split_once("..")
                        .and_then(|(s, e)| Some((s.parse().ok()?, e.parse().ok()?)))
                        .and_then(|(s, e)| map.find_in_string(source, path, s, e))
                        .or_else(|| map.find(path)),
                    None => map.find(&lookup),
                };
                d
            })
            .collect(),
    }
}

/// Compiles one group: `effect` holds its fields (and the file's shared ones), `links` its
/// events, and `prefix` (`groups[1].`, or empty for the top level) is put before every path
/// its diagnostics name.
pub(crate) fn compile_group(
    effect: &EffectSpec,
    links: &GroupLinks,
    prefix: &str,
    located: &dyn Fn(Vec<(Diagnostic, String)>) -> Diagnostics,
) -> Result<CompiledEffect, CompileError> {
    let prefixed = |items: Vec<(Diagnostic, String)>| located(prefixed(items, prefix));
    // Files the effect names (a height field's image, a mesh, a vector field) are read first: the
    // checks and everything after see what they hold.
    let mut effect = effect.clone();
    let mut read = crate::base::check::Checker::default();
    crate::features::colliders::height_image::read_height_images(
        &mut effect.collide,
        effect.base_dir.as_deref(),
        &mut read,
    );
    crate::features::emitter::read_mesh_shapes(
        &mut effect.emitters,
        effect.base_dir.as_deref(),
        &mut read,
    );
    crate::features::colliders::mesh::read_meshes(
        &mut effect.collide,
        effect.base_dir.as_deref(),
        &mut read,
    );
    crate::features::scene::read_scene(&mut effect.scene, effect.base_dir.as_deref(), &mut read);
    crate::features::forces::vector_field::read_vector_fields(
        &mut effect.forces,
        effect.base_dir.as_deref(),
        &mut read,
    );
    if !read.errors.is_empty() {
        return Err(CompileError::Invalid(prefixed(read.errors)));
    }
    let checker = validate::check_effect(&effect);
    if !checker.errors.is_empty() {
        return Err(CompileError::Invalid(prefixed(checker.errors)));
    }
    // The event inputs' spawn rules join the group's own emitters after the checks (they are
    // not in the file).
    effect.emitters.extend(links.input_emitters.iter().cloned());
    let effect = &effect;
    let mut ir = lower::lower(effect);
    ir.events.clone_from(&links.events);
    ir.event_inputs.clone_from(&links.inputs);
    // A budget's calibration is remembered by the effect's content, its seed aside
    // (`calibration::accuracy::choose`): the IR as it would be lowered with seed 0.
    if ir.accuracy.is_some() {
        let mut unseeded = lower::lower(&EffectSpec {
            seed: 0,
            ..effect.clone()
        });
        unseeded.events.clone_from(&links.events);
        unseeded.event_inputs.clone_from(&links.inputs);
        let mut h = std::collections::hash_map::DefaultHasher::new();
        std::hash::Hash::hash(&format!("{unseeded:?}"), &mut h);
        if let Some(a) = &mut ir.accuracy {
            a.content = Some(std::hash::Hasher::finish(&h));
        }
    }
    let base = effect.base_dir.as_deref();
    let look = (prefix, effect.step_only);
    if let Some(spec) = &effect.render.texture {
        let path = ValuePath::root().field("render").field("texture");
        let read = texture::TextureIr::load(spec, base);
        let mut texture = look_file(path.field("file"), look, read, located, |why| {
            texture::TextureIr::stand_in(spec, why)
        })?;
        if let Some(second) = &spec.second {
            let read = texture.load_second(second, base);
            let loaded = look_file(
                path.field("second").field("file"),
                look,
                read,
                located,
                |why| texture.stand_in_second(second, why),
            )?;
            texture.second = Some(Box::new(loaded));
        }
        ir.render.texture = Some(texture);
    }
    if let Some(spec) = &effect.render.mesh {
        let path = ValuePath::root()
            .field("render")
            .field("mesh")
            .field("file");
        let read = particle_mesh::MeshIr::load(spec, base);
        ir.render.mesh = Some(look_file(path, look, read, located, |why| {
            particle_mesh::MeshIr::stand_in(spec, why)
        })?);
    }
    if let (Some(lit), Some(texture)) = (&effect.render.lit, &ir.render.texture) {
        for (field, file) in lit.map_files() {
            let path = ValuePath::root()
                .field("render")
                .field("lit")
                .field("normals")
                .variant(lit.normals_name())
                .field(field);
            let read = texture::TextureIr::load_lit_map(file, texture, base);
            let map = look_file(path, look, read, located, |why| {
                texture::TextureIr::stand_in_lit_map(file, texture, why)
            })?;
            ir.render.lit_maps.push(map);
        }
    }
    let names: Vec<&'static str> = effect.forces.iter().map(|f| f.name()).collect();
    let (layout, warnings) = passes::run(&mut ir, &names, &crate::calibration::accuracy::choose)
        .map_err(|c| CompileError::Invalid(prefixed(c.errors)))?;
    let wgsl = wgsl::emit_module(&ir, &layout);
    naga_check::validate(&wgsl)?;
    let draw_wgsl = wgsl::draw::emit(&ir, &layout, &wgsl::draw::DrawShape::single(&ir));
    naga_check::validate(&draw_wgsl)?;
    let trail_wgsl = match ir.render.trail {
        Some(_) => {
            let shape = wgsl::draw::DrawShape::single(&ir);
            let source = wgsl::trail::emit(&ir, &layout, &shape);
            naga_check::validate(&source)?;
            Some(source)
        }
        None => None,
    };
    let flock_search_wgsl = match &ir.flock {
        Some(flock) => flock.emit_search_module(&ir.name, ir.capacity, &layout),
        None => None,
    };
    if let Some(source) = &flock_search_wgsl {
        naga_check::validate(source)?;
    }
    Ok(CompiledEffect {
        ir,
        layout,
        wgsl,
        draw_wgsl,
        trail_wgsl,
        flock_search_wgsl,
        warnings: prefixed(warnings),
    })
}

/// What the compiler adds to one group for its events.
#[derive(Clone, Debug, Default)]
pub(crate) struct GroupLinks {
    /// Events the group fires.
    pub events: Vec<EventIr>,
    /// Events the group is fed by.
    pub inputs: Vec<EventInputIr>,
    /// Their spawn rules, appended to the group's emitters.
    pub(crate) input_emitters: Vec<Emitter>,
}

/// The path of the first graph field an effect uses (`groups` or `events`), if any.
pub fn graph_field(effect: &EffectSpec) -> Option<ValuePath> {
    if !effect.groups.is_empty() {
        Some(ValuePath::root().field("groups"))
    } else if !effect.events.is_empty() {
        Some(ValuePath::root().field("events"))
    } else {
        None
    }
}

/// A file the look names (a texture, a lit map, a mesh) at `path`, as `read` gave it; for an
/// effect compiled to be stepped only (`look.1`), `stand_in(why)` where it could not be read:
/// nothing will be drawn, and a draw asked for after all says why not. Otherwise the located
/// error, its path put after `look.0` (the group's prefix).
fn look_file<T>(
    path: ValuePath,
    (prefix, step_only): (&str, bool),
    read: Result<T, String>,
    located: &dyn Fn(Vec<(Diagnostic, String)>) -> Diagnostics,
    stand_in: impl FnOnce(String) -> T,
) -> Result<T, CompileError> {
    match read {
        Ok(loaded) => Ok(loaded),
        Err(message) if step_only => Ok(stand_in(format!(
            "{}: {message}",
            join(prefix, &path.display)
        ))),
        Err(message) => Err(CompileError::Invalid(located(prefixed(
            vec![(Diagnostic::error(path.display, message), path.lookup)],
            prefix,
        )))),
    }
}

/// Puts `prefix` (`groups[0].`) before every path of `items`.
pub(crate) fn prefixed(
    items: Vec<(Diagnostic, String)>,
    prefix: &str,
) -> Vec<(Diagnostic, String)> {
    if prefix.is_empty() {
        return items;
    }
    items
        .into_iter()
        .map(|(mut d, lookup)| {
            d.path = join(prefix, &d.path);
            (d, join(prefix, &lookup))
        })
        .collect()
}

fn join(prefix: &str, path: &str) -> String {
    if path.is_empty() {
        prefix.trim_end_matches('.').to_string()
    } else {
        format!("{prefix}{path}")
    }
}
