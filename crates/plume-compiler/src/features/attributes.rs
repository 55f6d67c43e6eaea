//! Attributes an effect declares for its particles (`attributes: {"heat": (spawn: "...",
//! rate: "...")}`): numbers or vectors each particle carries, given a value at spawn by an
//! expression and, optionally, changed once a step by another (`update`: the new value) or
//! integrated from one (`rate`: the change per second, added times dt). Custom forces, the
//! draw's expressions (`render.color_by`, ...) and other attributes' changes read them by name.
//!
//! This module owns the schema, the checks (mistakes located inside each string), the lowered
//! form, the WGSL (a function per spawn value and per change, the context the custom forces
//! read them through) and the f64 twin the reference runs. Only what a scene requires is kept:
//! an attribute that nothing reads is not stored, and one that is a constant never changed is
//! read as that constant (`crate::expr::typed::AttrName::constant`).
//!
//! When they are evaluated: a spawn value as the particle spawns, from its position and
//! velocity then, the time of the step and its random numbers; a change once a step, after the
//! motion, from the position and velocity the step leaves, the time and age at the step's
//! start, and every attribute's value before the step (all change together).

use std::collections::BTreeMap;

use glam::DVec3;
use serde::Deserialize;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::stream;
use crate::base::writer::{f32_lit, Writer};
pub(crate) use crate::expr::eval::MAX_ATTRIBUTES;
use crate::expr::eval::{eval, Attrs, Inputs, Value};
use crate::expr::typed::{AttrName, Node};
use crate::expr::{self, Expr, ExprError, Names, Ty, Var};

/// The most 4-byte words the declared attributes may take together (a vec3 takes 3): 64
/// bytes, on top of the built-in ones, keeps a particle within a few cache lines and its
/// struct well inside what every adapter's storage binding holds at the largest capacities.
pub(crate) const MAX_WORDS: u32 = 16;

/// The kept attributes' stored words of one particle, in the layout's order; 0 past the last.
pub type Words = [f64; MAX_WORDS as usize];

/// What a spawn value may read: the position and velocity it spawned with, and the time.
const SPAWN_VARS: &[Var] = &[Var::X, Var::V, Var::T];

/// One declared attribute.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Attribute {
    /// Its value at spawn, an expression of x, v, t, rand(k), params and dt; its type (f32 or
    /// vec3) is the attribute's.
    pub spawn: String,
    /// Its change per second, integrated once a step: value += dt · rate.
    #[serde(default)]
    pub rate: Option<String>,
    /// Its new value, computed once a step.
    #[serde(default)]
    pub update: Option<String>,
    /// In a group fed by events, its children start with the firing particle's attribute of
    /// the same name instead of `spawn` (`features::inherit`).
    #[serde(default)]
    pub inherit: bool,
}

/// The file's `attributes`, by name.
pub(crate) type Declared = BTreeMap<String, Attribute>;

/// How an attribute changes over a particle's life.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Change {
    /// It keeps its spawn value.
    None,
    /// Its change per second, added times dt once a step.
    Rate(Expr),
    /// Its new value, once a step.
    Set(Expr),
}

/// A lowered attribute.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct AttributeIr {
    /// As written in the file.
    pub name: String,
    /// f32 or vec3.
    pub ty: Ty,
    /// Its value at spawn.
    pub spawn: Expr,
    /// Its change over life.
    pub change: Change,
}

impl AttributeIr {
    /// 4-byte words it takes.
    pub(crate) fn width(&self) -> u8 {
        match self.ty {
            Ty::Vec3 => 3,
            _ => 1,
        }
    }

    fn wgsl_ty(&self) -> &'static str {
        match self.ty {
            Ty::Vec3 => "vec3<f32>",
            _ => "f32",
        }
    }

    /// Whether its value changes after spawn.
    pub(crate) fn changes(&self) -> bool {
        self.change != Change::None
    }

    fn change_expr(&self) -> Option<&Expr> {
        match &self.change {
            Change::None => None,
            Change::Rate(e) | Change::Set(e) => Some(e),
        }
    }
}

/// The attributes of an effect, in name order (their index is their place here).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AttributesIr {
    /// Every declared attribute, kept or not.
    pub(crate) list: Vec<AttributeIr>,
    /// The effect's dt (s), the step a rate is integrated over.
    pub dt: f64,
    /// The effect's seed mix, for `rand(k)`.
    pub seed_mix: u32,
}

fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
        && chars.all(|c| c.is_alphanumeric() || c == '_')
}

/// Compiles a spawn value of either type (a bool is a mistake at the string's start).
fn compile_spawn(text: &str, names: Names) -> Result<Expr, ExprError> {
    let scope = names.scope(SPAWN_VARS, "a spawn value");
    match expr::compile_in(text, Ty::Scalar, &scope) {
        Ok(e) => Ok(e),
        Err(first) => expr::compile_in(text, Ty::Vec3, &scope).map_err(|_| first),
    }
}

fn change_role(name: &str, rate: bool) -> String {
    match rate {
        true => format!("`{name}`'s rate"),
        false => format!("`{name}`'s update"),
    }
}

/// What the expressions of an effect see of its attributes: each one's name, its type (its
/// spawn value's; f32 where that does not compile) and its constant value when its spawn
/// value folds to one and it never changes.
pub(crate) fn names(declared: &Declared, names: Names) -> Vec<AttrName> {
    let names = Names {
        attrs: &[],
        ..names
    };
    declared
        .iter()
        .map(|(name, a)| {
            let spawn = compile_spawn(&a.spawn, names).ok();
            let constant = spawn.as_ref().and_then(|e| match e.node {
                _ if a.rate.is_some() || a.update.is_some() || a.inherit => None,
                Node::Scalar(x) => Some(DVec3::splat(x)),
                Node::Vector(v) => Some(v),
                _ => None,
            });
            AttrName {
                name: name.clone(),
                ty: spawn.map_or(Ty::Scalar, |e| e.ty),
                constant,
            }
        })
        .collect()
}

/// Records the mistakes of `declared` (at `path`, the file's `attributes`) in `c`: names an
/// expression cannot use or that hide another name, too many, expressions that do not
/// compile, a rate and an update both given. `names.attrs` is [`names`]'s result.
pub(crate) fn check(c: &mut Checker, path: &ValuePath, declared: &Declared, names: Names) {
    use crate::expr::typed::{EVERY_VARIABLE, FUNCTIONS};
    if declared.len() > MAX_ATTRIBUTES {
        c.error(
            path,
            format!(
                "declares {} attributes, more than the {MAX_ATTRIBUTES} an effect may have",
                declared.len()
            ),
        );
    }
    let words: u32 = names
        .attrs
        .iter()
        .map(|a| if a.ty == Ty::Vec3 { 3 } else { 1 })
        .sum();
    if words > MAX_WORDS {
        c.error(
            path,
            format!("the attributes take {words} words (a vec3 takes 3), more than the {MAX_WORDS} a particle may carry"),
        );
    }
    for (name, a) in declared {
        let p = path.field(name);
        if !is_identifier(name) {
            c.error(
                &p,
                format!("`{name}` is not a name an expression can use: start with a letter, then letters, digits or _"),
            );
        } else if name == "dt"
            || EVERY_VARIABLE.iter().any(|v| v.name() == name)
            || FUNCTIONS.iter().any(|(f, _)| f == name)
            || names.params.contains_key(name)
        {
            c.error(
                &p,
                format!("`{name}` is already a variable, function or param in expressions: pick another name"),
            );
        }
        if let Err(e) = compile_spawn(&a.spawn, names) {
            c.error_in_string(&p.field("spawn"), e.start, e.end, e.message);
        }
        if a.rate.is_some() && a.update.is_some() {
            c.error(
                &p.field("update"),
                "give a rate (integrated) or an update (the new value), not both",
            );
        }
        let ty = names
            .attrs
            .iter()
            .find(|n| n.name == *name)
            .map_or(Ty::Scalar, |n| n.ty);
        for (field, text, rate) in [("rate", &a.rate, true), ("update", &a.update, false)] {
            let Some(text) = text else { continue };
            let role = change_role(name, rate);
            let scope = names.scope_with_attrs(crate::expr::typed::VARIABLES, &role);
            if let Err(e) = expr::compile_in(text, ty, &scope) {
                c.error_in_string(&p.field(field), e.start, e.end, e.message);
            }
        }
    }
}

impl AttributesIr {
    /// Lowers `declared` (after [`check`] passed); `names.attrs` is [`names`]'s result.
    pub(crate) fn lower(declared: &Declared, names: Names, seed_mix: u32) -> Self {
        let list = declared
            .iter()
            .zip(names.attrs)
            .map(|((name, a), n)| {
                let spawn = compile_spawn(&a.spawn, names).expect("checked before lowering");
                let compile = |text: &str, rate| {
                    let role = change_role(name, rate);
                    let scope = names.scope_with_attrs(crate::expr::typed::VARIABLES, &role);
                    expr::compile_in(text, n.ty, &scope).expect("checked before lowering")
                };
                let change = match (&a.rate, &a.update) {
                    (Some(r), _) => Change::Rate(compile(r, true)),
                    (None, Some(u)) => Change::Set(compile(u, false)),
                    (None, None) => Change::None,
                };
                AttributeIr {
                    name: name.clone(),
                    ty: n.ty,
                    spawn,
                    change,
                }
            })
            .collect();
        Self {
            list,
            dt: names.dt,
            seed_mix,
        }
    }

    /// The attributes kept (a bit set of indices), given those that the forces and the draw
    /// read (`read`): those, and what their changes read in turn.
    pub fn kept(&self, read: u64) -> u64 {
        let mut kept = read;
        loop {
            let more = self
                .list
                .iter()
                .enumerate()
                .filter(|(i, _)| kept & (1 << i) != 0)
                .filter_map(|(_, a)| a.change_expr())
                .fold(kept, |set, e| set | e.attrs_read());
            if more == kept {
                return kept;
            }
            kept = more;
        }
    }

    /// The kept attributes with their indices.
    pub(crate) fn iter_kept(&self, kept: u64) -> impl Iterator<Item = (usize, &AttributeIr)> {
        self.list
            .iter()
            .enumerate()
            .filter(move |(i, _)| kept & (1 << i) != 0)
    }

    /// Whether a kept attribute's change reads the particle's age or lifetime (the layout
    /// then keeps the spawn step).
    pub(crate) fn reads_age_or_life(&self, kept: u64) -> bool {
        self.iter_kept(kept)
            .filter_map(|(_, a)| a.change_expr())
            .any(|e| e.reads(Var::Age) || e.reads(Var::Life))
    }

    /// Whether a kept attribute's spawn value or change reads the time `t` (the kernels then
    /// keep the whole time, not its remainder modulo 256 s).
    pub fn reads_time(&self, kept: u64) -> bool {
        self.iter_kept(kept)
            .any(|(_, a)| a.spawn.reads(Var::T) || a.change_expr().is_some_and(|e| e.reads(Var::T)))
    }

    /// Whether a kept attribute's spawn value or change reads the gradient noise through `op`.
    pub(crate) fn uses(&self, kept: u64, op: crate::expr::typed::Op1) -> bool {
        self.iter_kept(kept)
            .any(|(_, a)| a.spawn.uses(op) || a.change_expr().is_some_and(|e| e.uses(op)))
    }

    /// Sets every live param of index `index` to `value` (the reference's twin of the host).
    pub fn set_param(&mut self, index: u32, value: f64) {
        for a in &mut self.list {
            a.spawn.set_param(index, value);
            if let Change::Rate(e) | Change::Set(e) = &mut a.change {
                e.set_param(index, value);
            }
        }
    }

    /// One line per kept attribute for `--emit ir` (none without attributes).
    pub fn describe(&self, kept: u64) -> Vec<String> {
        self.list
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let change = match &a.change {
                    Change::None => "kept from spawn".to_string(),
                    Change::Rate(e) => format!("rate of {} nodes", e.size()),
                    Change::Set(e) => format!("update of {} nodes", e.size()),
                };
                match kept & (1 << i) != 0 {
                    true => format!(
                        "{} {} ({} bytes): spawn value of {} nodes, {change}",
                        a.name,
                        a.ty.name(),
                        4 * a.width(),
                        a.spawn.size()
                    ),
                    false if !a.changes() && expr::fold::is_constant(&a.spawn) => format!(
                        "{} {}: a constant, folded where it is read, not stored",
                        a.name,
                        a.ty.name()
                    ),
                    false => format!("{} {}: read by nothing, not stored", a.name, a.ty.name()),
                }
            })
            .collect()
    }

    // ---- f64 twin ----

    fn inputs(&self, x: DVec3, v: DVec3, t: f64, id: u32) -> Inputs {
        Inputs {
            x,
            v,
            t,
            seed_mix: self.seed_mix,
            id,
            ..Inputs::default()
        }
    }

    /// The kept attributes' values at spawn of particle `id`, spawned at time `t` with
    /// position `x` and velocity `v` (the others 0).
    pub fn spawn_values(&self, kept: u64, x: DVec3, v: DVec3, t: f64, id: u32) -> Attrs {
        let mut out = Attrs::default();
        let inputs = self.inputs(x, v, t, id);
        for (i, a) in self.iter_kept(kept) {
            out[i] = as_stored(eval(&a.spawn, &inputs), a.ty);
        }
        out
    }

    /// The kept attributes' values after a step, from their values before it (`inputs.attrs`)
    /// and the particle as the step leaves it.
    pub fn step_values(&self, kept: u64, inputs: &Inputs) -> Attrs {
        let mut out = inputs.attrs;
        for (i, a) in self.iter_kept(kept) {
            out[i] = match &a.change {
                Change::None => continue,
                Change::Set(e) => as_stored(eval(e, inputs), a.ty),
                Change::Rate(e) => {
                    let rate = as_stored(eval(e, inputs), a.ty);
                    (inputs.attrs[i] + rate * self.dt).clamp(
                        DVec3::splat(-expr::VALUE_BOUND),
                        DVec3::splat(expr::VALUE_BOUND),
                    )
                }
            };
        }
        out
    }

    /// The kept attributes' stored words in layout order (a vec3's three in turn).
    pub fn words(&self, kept: u64, values: &Attrs) -> Words {
        let mut out = Words::default();
        let all = self.iter_kept(kept).flat_map(|(i, a)| {
            let v = values[i];
            match a.ty {
                Ty::Vec3 => vec![v.x, v.y, v.z],
                _ => vec![v.x],
            }
        });
        for (slot, word) in out.iter_mut().zip(all) {
            *slot = word;
        }
        out
    }

    /// The inverse of [`Self::words`].
    pub fn from_words(&self, kept: u64, words: &[f64]) -> Attrs {
        let mut out = Attrs::default();
        let mut at = 0;
        for (i, a) in self.iter_kept(kept) {
            let w = |k: usize| words.get(at + k).copied().unwrap_or(0.0);
            out[i] = match a.ty {
                Ty::Vec3 => DVec3::new(w(0), w(1), w(2)),
                _ => DVec3::new(w(0), 0.0, 0.0),
            };
            at += usize::from(a.width());
        }
        out
    }

    // ---- WGSL ----

    /// `, a0: f32, a2: vec3<f32>`: the kept attributes as a function's trailing parameters.
    pub(crate) fn params_wgsl(&self, kept: u64) -> String {
        self.iter_kept(kept)
            .map(|(i, a)| format!(", a{i}: {}", a.wgsl_ty()))
            .collect()
    }

    /// `, v0, vec3<f32>(v1, v2, v3)`: the kept attributes as trailing arguments, from their
    /// stored words `field(i)` (the WGSL names of attribute i's words).
    pub(crate) fn args_wgsl(&self, kept: u64, field: impl Fn(usize) -> Vec<String>) -> String {
        self.iter_kept(kept)
            .map(|(i, a)| {
                let words = field(i);
                match a.ty {
                    Ty::Vec3 => format!(", vec3<f32>({})", words.join(", ")),
                    _ => format!(", {}", words[0]),
                }
            })
            .collect()
    }

    /// Emits `attr_spawn_I(x, v, t, ctx_id)` and, for those that change,
    /// `attr_change_I(x, v, t, age, ctx_life, ctx_id, <attributes>)` (the new value) for each
    /// kept attribute: the WGSL twins of [`Self::spawn_values`] and [`Self::step_values`].
    pub(crate) fn emit_fns(&self, w: &mut Writer, kept: u64) {
        let bound = f32_lit(expr::VALUE_BOUND);
        let clamps = |w: &mut Writer| {
            w.line(format!(
                "let cx = clamp(x, vec3<f32>(-{bound}), vec3<f32>({bound}));"
            ));
            w.line(format!(
                "let cv = clamp(v, vec3<f32>(-{bound}), vec3<f32>({bound}));"
            ));
        };
        let params = self.params_wgsl(kept);
        for (i, a) in self.iter_kept(kept) {
            let ty = a.wgsl_ty();
            w.comment(format!("attributes.{}: its value at spawn.", a.name));
            w.block(
                format!(
                    "fn attr_spawn_{i}(x: vec3<f32>, v: vec3<f32>, t: f32, ctx_id: u32) -> {ty}"
                ),
                |w| {
                    clamps(w);
                    let value = expr::emit::Emitter::new(w, stream::CUSTOM).value(&a.spawn);
                    w.line(format!("return {};", widen(&value, &a.spawn, a.ty)));
                },
            );
            let Some(e) = a.change_expr() else { continue };
            w.comment(format!(
                "attributes.{}: its value after a step, from the values before it.",
                a.name
            ));
            w.block(
                format!("fn attr_change_{i}(x: vec3<f32>, v: vec3<f32>, t: f32, age: f32, ctx_life: f32, ctx_id: u32{params}) -> {ty}"),
                |w| {
                    clamps(w);
                    let value = expr::emit::Emitter::new(w, stream::CUSTOM).value(e);
                    let value = widen(&value, e, a.ty);
                    match &a.change {
                        Change::Rate(_) => w.line(format!(
                            "return clamp(a{i} + {value} * {}, {ty}(-{bound}), {ty}({bound}));",
                            f32_lit(self.dt)
                        )),
                        _ => w.line(format!("return {value};")),
                    }
                },
            );
        }
    }

    /// Declares `ctx_aI` for each attribute that a custom force reads (`read`), as the
    /// particle context the forces' `accel` reads them from.
    pub(crate) fn emit_context(&self, w: &mut Writer, read: u64) {
        for (i, a) in self.iter_kept(read) {
            w.line(format!("var<private> ctx_a{i}: {};", a.wgsl_ty()));
        }
    }

    /// Sets `ctx_aI` for each attribute that a custom force reads (`read`) from `value(i)`,
    /// a WGSL expression of its value.
    pub(crate) fn emit_set_context(
        &self,
        w: &mut Writer,
        read: u64,
        value: impl Fn(usize) -> String,
    ) {
        for (i, _) in self.iter_kept(read) {
            w.line(format!("ctx_a{i} = {};", value(i)));
        }
    }
}

/// `value` (of `e`'s type) as a value of type `ty` (a number stands for three equal ones).
fn widen(value: &str, e: &Expr, ty: Ty) -> String {
    match (e.ty, ty) {
        (Ty::Scalar, Ty::Vec3) => format!("vec3<f32>({value})"),
        _ => value.to_string(),
    }
}

/// An evaluated value as an attribute holds it (a number in `x`).
fn as_stored(value: Value, ty: Ty) -> DVec3 {
    match ty {
        Ty::Vec3 => value.v(),
        _ => DVec3::new(value.s(), 0.0, 0.0),
    }
}
