//! Colour and size set by expressions (`render.color_by`, `render.size_by`): the colour stops'
//! RGB multiplied by a vec3 of the particle, and its size (width and height) by an f32, each
//! written in the custom forces' language ([`crate::expr`]): checked with its mistakes located
//! inside the string, folded, written into the draw module as a function and interpreted from
//! the same tree in f64 by the reference drawing (runtime `oracle`).
//!
//! They read the particle as the draw sees it: its position `x`, velocity `v`, `age` and
//! `life` (seconds, whole steps as the kernels count them; `life` 0 for a particle that never
//! dies), `rand(k)` and the draws built on it, the params (as the file gives them: the draw
//! reads no live params) and `dt`. A colour factor is kept within [0, [`COLOR_MOST`]] and a size
//! factor at least 0, so neither can make a NaN, a negative size or more light than the
//! compute renderer's fixed-point sums hold.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::stream;
use crate::base::writer::{f32_lit, Writer};
use crate::expr::eval::{eval, Inputs};
use crate::expr::{self, Expr, Names, Ty, Var};
use crate::features::looks::COLOR_MOST;

const VARS: &[Var] = &[Var::X, Var::V, Var::Age, Var::Life];

/// What the draw multiplies a particle's colour and size by.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LookBy {
    /// Multiplies the colour stops' RGB (a vec3).
    pub color: Option<Expr>,
    /// Multiplies the size (and the height, with `size_y`).
    pub size: Option<Expr>,
}

/// What a particle is, for the f64 twins: position, velocity, age and lifetime (s; 0 for a
/// particle that never dies), and its id.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Seen {
    /// Position (m).
    pub x: DVec3,
    /// Velocity (m/s).
    pub v: DVec3,
    /// Age (s).
    pub age: f64,
    /// Lifetime (s), 0 when it never dies.
    pub life: f64,
    /// Its id.
    pub id: u32,
}

fn compile(text: &str, ty: Ty, role: &str, names: Names) -> Result<Expr, expr::ExprError> {
    // The draw module reads no step parameters: params are the file's values.
    let names = Names {
        live: false,
        ..names
    };
    expr::compile_in(text, ty, &names.scope(VARS, role))
}

impl LookBy {
    /// Records mistakes in `color_by` and `size_by` (the render section's strings, at `path`,
    /// the render section) in `c`.
    pub fn check(
        c: &mut Checker,
        path: &ValuePath,
        (color_by, size_by): (Option<&str>, Option<&str>),
        names: Names,
    ) {
        if let Some(Err(e)) = color_by.map(|t| compile(t, Ty::Vec3, "a colour factor", names)) {
            c.error_in_string(&path.field("color_by"), e.start, e.end, e.message);
        }
        if let Some(Err(e)) = size_by.map(|t| compile(t, Ty::Scalar, "a size factor", names)) {
            c.error_in_string(&path.field("size_by"), e.start, e.end, e.message);
        }
    }

    /// Lowers the strings (after [`LookBy::check`] passed).
    pub fn lower((color_by, size_by): (Option<&str>, Option<&str>), names: Names) -> Self {
        let checked = "checked before lowering";
        Self {
            color: color_by.map(|t| compile(t, Ty::Vec3, "a colour factor", names).expect(checked)),
            size: size_by.map(|t| compile(t, Ty::Scalar, "a size factor", names).expect(checked)),
        }
    }

    fn exprs(&self) -> impl Iterator<Item = &Expr> {
        self.color.iter().chain(&self.size)
    }

    /// Whether either reads the particle's age or lifetime (the draw then needs its ages).
    pub fn reads_age_or_life(&self) -> bool {
        self.exprs()
            .any(|e| e.reads(Var::Age) || e.reads(Var::Life))
    }

    /// Whether either draws random numbers.
    pub fn draws_random(&self) -> bool {
        self.exprs().any(|e| e.draws_random())
    }

    /// Whether either reads the velocity.
    pub fn reads_velocity(&self) -> bool {
        self.exprs().any(|e| e.reads(Var::V))
    }

    /// Emits `color_by(x, v, age, ctx_life, ctx_id) -> vec3<f32>` and `size_by(...) -> f32`
    /// for those there are: the WGSL twins of [`Self::color_factor`] and [`Self::size_factor`].
    pub fn emit_fns(&self, w: &mut Writer) {
        let bound = f32_lit(expr::VALUE_BOUND);
        let clamp = |w: &mut Writer| {
            w.line(format!(
                "let cx = clamp(x, vec3<f32>(-{bound}), vec3<f32>({bound}));"
            ));
            w.line(format!(
                "let cv = clamp(v, vec3<f32>(-{bound}), vec3<f32>({bound}));"
            ));
        };
        if let Some(e) = &self.color {
            w.comment("render.color_by: multiplies the colour stops' RGB, within [0, 128].");
            w.block(
                "fn color_by(x: vec3<f32>, v: vec3<f32>, age: f32, ctx_life: f32, ctx_id: u32) -> vec3<f32>",
                |w| {
                    clamp(w);
                    let value = expr::emit::Emitter::new(w, stream::CUSTOM).value(e);
                    w.line(format!(
                        "return clamp({value}, vec3<f32>(0.0), vec3<f32>({}));",
                        f32_lit(COLOR_MOST)
                    ));
                },
            );
        }
        if let Some(e) = &self.size {
            w.comment("render.size_by: multiplies the size, at least 0.");
            w.block(
                "fn size_by(x: vec3<f32>, v: vec3<f32>, age: f32, ctx_life: f32, ctx_id: u32) -> f32",
                |w| {
                    clamp(w);
                    let value = expr::emit::Emitter::new(w, stream::CUSTOM).value(e);
                    w.line(format!("return max({value}, 0.0);"));
                },
            );
        }
    }

    fn inputs(p: &Seen, seed_mix: u32) -> Inputs {
        Inputs {
            x: p.x,
            v: p.v,
            age: p.age,
            life: p.life,
            seed_mix,
            id: p.id,
            ..Inputs::default()
        }
    }

    /// What the colour's RGB is multiplied by for particle `p` of an effect of `seed_mix`
    /// (1 without `color_by`).
    pub fn color_factor(&self, p: &Seen, seed_mix: u32) -> DVec3 {
        match &self.color {
            Some(e) => eval(e, &Self::inputs(p, seed_mix))
                .v()
                .clamp(DVec3::ZERO, DVec3::splat(COLOR_MOST)),
            None => DVec3::ONE,
        }
    }

    /// What the size is multiplied by for particle `p` (1 without `size_by`).
    pub fn size_factor(&self, p: &Seen, seed_mix: u32) -> f64 {
        match &self.size {
            Some(e) => eval(e, &Self::inputs(p, seed_mix)).s().max(0.0),
            None => 1.0,
        }
    }
}
