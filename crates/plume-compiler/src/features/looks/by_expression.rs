//! Colour, opacity and size set by expressions (`render.color_by`, `alpha_by`, `size_by`): the
//! colour stops' RGB multiplied by a vec3 of the particle, their alpha by an f32 and its size
//! (width and height) by an f32, each
//! written in the custom forces' language ([`crate::expr`]): checked with its mistakes located
//! inside the string, folded, written into the draw module as a function and interpreted from
//! the same tree in f64 by the reference drawing (runtime `oracle`).
//!
//! They read the particle as the draw sees it: its position `x`, velocity `v`, `age` and
//! `life` (seconds, whole steps as the kernels count them; `life` 0 for a particle that never
//! dies), the frame's time `t` (steps done × dt), `rand(k)` and the draws built on it, the
//! params (as the file gives them: the draw reads no live params) and `dt`. A colour factor is kept within 0 to `COLOR_MOST`, an
//! opacity factor within [0, 1] and a size factor at least 0, so none can make a NaN, a
//! negative size, an alpha past 1 or more light than the compute renderer's fixed-point sums
//! hold.

use glam::DVec3;

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::rng::stream;
use crate::base::writer::{f32_lit, Writer};
use crate::expr::eval::{eval, Inputs};
use crate::expr::{self, Expr, Names, Ty, Var};
use crate::features::looks::COLOR_MOST;

const VARS: &[Var] = &[Var::X, Var::V, Var::T, Var::Age, Var::Life];

/// What the draw multiplies a particle's colour and size by.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LookBy {
    /// Multiplies the colour stops' RGB (a vec3).
    pub(crate) color: Option<Expr>,
    /// Multiplies the colour's alpha.
    pub(crate) alpha: Option<Expr>,
    /// Multiplies the size (and the height, with `size_y`).
    pub(crate) size: Option<Expr>,
    /// The t at which the colour (and opacity) stops are read, instead of the life fraction.
    pub(crate) color_t: Option<Expr>,
    /// The flipbook frame shown, instead of the texture's `play`: its whole part, wrapped
    /// around the frames (`frame_of`).
    pub(crate) frame: Option<Expr>,
}

/// The frame a `frame_by` value shows of `frames`: its whole part (at least 0, at most 2^24,
/// where an f32 still counts whole numbers) wrapped around the frames; the f64 twin of the
/// draw's.
pub(crate) fn frame_of(value: f64, frames: u32) -> u32 {
    ((value.floor().clamp(0.0, FRAME_MOST)) as u32) % frames.max(1)
}

/// The largest whole value `frame_by` counts up to (2^24).
const FRAME_MOST: f64 = 16_777_216.0;

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
    /// Its attributes' values (`features::attributes`), by index.
    pub attrs: crate::expr::eval::Attrs,
    /// The simulation time of the frame drawn (s): steps done × dt.
    pub t: f64,
}

fn compile(text: &str, ty: Ty, role: &str, names: Names) -> Result<Expr, expr::ExprError> {
    // The draw module reads no step parameters: params are the file's values.
    let names = Names {
        live: false,
        ..names
    };
    expr::compile_in(text, ty, &names.scope_with_attrs(VARS, role))
}

/// The render section's strings: `color_by`, `alpha_by`, `size_by`, `color_t` and `frame_by`.
pub type Written<'a> = [Option<&'a str>; 5];

/// Each string's field, type and role, in [`Written`]'s order.
const FIELDS: [(&str, Ty, &str); 5] = [
    ("color_by", Ty::Vec3, "a colour factor"),
    ("alpha_by", Ty::Scalar, "an opacity factor"),
    ("size_by", Ty::Scalar, "a size factor"),
    ("color_t", Ty::Scalar, "a colour stop's t"),
    ("frame_by", Ty::Scalar, "a flipbook frame"),
];

impl LookBy {
    /// Records mistakes in the strings (at `path`, the render section) in `c`.
    pub(crate) fn check(c: &mut Checker, path: &ValuePath, written: Written, names: Names) {
        for (text, (field, ty, role)) in written.into_iter().zip(FIELDS) {
            if let Some(Err(e)) = text.map(|t| compile(t, ty, role, names)) {
                c.error_in_string(&path.field(field), e.start, e.end, e.message);
            }
        }
    }

    /// Lowers the strings (after [`LookBy::check`] passed).
    pub(crate) fn lower(written: Written, names: Names) -> Self {
        let [color, alpha, size, color_t, frame] = std::array::from_fn(|i| {
            let (_, ty, role) = FIELDS[i];
            written[i].map(|t| compile(t, ty, role, names).expect("checked before lowering"))
        });
        Self {
            color,
            alpha,
            size,
            color_t,
            frame,
        }
    }

    fn exprs(&self) -> impl Iterator<Item = &Expr> {
        self.color
            .iter()
            .chain(&self.alpha)
            .chain(&self.size)
            .chain(&self.color_t)
            .chain(&self.frame)
    }

    /// Whether any reads the particle's age or lifetime (the draw then needs its ages).
    pub(crate) fn reads_age_or_life(&self) -> bool {
        self.exprs()
            .any(|e| e.reads(Var::Age) || e.reads(Var::Life))
    }

    /// Whether any reads the time (the functions then take it).
    pub fn reads_time(&self) -> bool {
        self.exprs().any(|e| e.reads(Var::T))
    }

    /// Whether any draws random numbers.
    pub(crate) fn draws_random(&self) -> bool {
        self.exprs().any(|e| e.draws_random())
    }

    /// The attributes they read (a bit set of indices).
    pub(crate) fn attrs_read(&self) -> u64 {
        self.exprs().fold(0, |set, e| set | e.attrs_read())
    }

    /// Whether any reads the gradient noise through `op` (`noise` or `curl`).
    pub(crate) fn uses(&self, op: crate::expr::typed::Op1) -> bool {
        self.exprs().any(|e| e.uses(op))
    }

    /// Whether any reads the velocity.
    pub(crate) fn reads_velocity(&self) -> bool {
        self.exprs().any(|e| e.reads(Var::V))
    }

    /// Emits `color_by(x, v, age, ctx_life, ctx_id, <attributes>) -> vec3<f32>`,
    /// `alpha_by(...) -> f32` and `size_by(...) -> f32` for those there are: the WGSL twins of
    /// [`Self::color_factor`], [`Self::alpha_factor`] and [`Self::size_factor`]. `attrs` are
    /// the kept attributes' parameters (`AttributesIr::params_wgsl`).
    pub(crate) fn emit_fns(&self, w: &mut Writer, attrs: &str) {
        let bound = f32_lit(expr::VALUE_BOUND);
        let most = f32_lit(COLOR_MOST);
        // Each function: its expression, name, what it returns, and its bounds.
        let fns = [
            (
                &self.color,
                "color_by",
                "vec3<f32>",
                format!("clamp(VALUE, vec3<f32>(0.0), vec3<f32>({most}))"),
            ),
            (
                &self.alpha,
                "alpha_by",
                "f32",
                "clamp(VALUE, 0.0, 1.0)".to_string(),
            ),
            (&self.size, "size_by", "f32", "max(VALUE, 0.0)".to_string()),
            (
                &self.color_t,
                "color_t",
                "f32",
                "clamp(VALUE, 0.0, 1.0)".to_string(),
            ),
            (
                &self.frame,
                "frame_by",
                "f32",
                format!("clamp(floor(VALUE), 0.0, {})", f32_lit(FRAME_MOST)),
            ),
        ];
        // The time, only where an expression reads it (the functions are unchanged otherwise).
        let t = match self.reads_time() {
            true => ", t: f32",
            false => "",
        };
        for (e, name, ty, bounded) in fns {
            let Some(e) = e else { continue };
            w.comment(format!("render.{name}: {bounded}, VALUE the expression."));
            w.block(
                format!("fn {name}(x: vec3<f32>, v: vec3<f32>, age: f32, ctx_life: f32, ctx_id: u32{attrs}{t}) -> {ty}"),
                |w| {
                    w.line(format!("let cx = clamp(x, vec3<f32>(-{bound}), vec3<f32>({bound}));"));
                    w.line(format!("let cv = clamp(v, vec3<f32>(-{bound}), vec3<f32>({bound}));"));
                    let value = expr::emit::Emitter::new(w, stream::CUSTOM).value(e);
                    w.line(format!("return {};", bounded.replace("VALUE", &value)));
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
            attrs: p.attrs,
            t: p.t,
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

    /// What the alpha is multiplied by for particle `p` (1 without `alpha_by`).
    pub fn alpha_factor(&self, p: &Seen, seed_mix: u32) -> f64 {
        match &self.alpha {
            Some(e) => eval(e, &Self::inputs(p, seed_mix)).s().clamp(0.0, 1.0),
            None => 1.0,
        }
    }

    /// The t at which particle `p`'s colour stops are read, when `color_t` gives one.
    pub fn color_t_at(&self, p: &Seen, seed_mix: u32) -> Option<f64> {
        self.color_t
            .as_ref()
            .map(|e| eval(e, &Self::inputs(p, seed_mix)).s().clamp(0.0, 1.0))
    }

    /// The flipbook frame particle `p` shows of `frames`, when `frame_by` gives one.
    pub fn frame_at(&self, p: &Seen, seed_mix: u32, frames: u32) -> Option<u32> {
        self.frame
            .as_ref()
            .map(|e| frame_of(eval(e, &Self::inputs(p, seed_mix)).s(), frames))
    }

    /// What the size is multiplied by for particle `p` (1 without `size_by`).
    pub fn size_factor(&self, p: &Seen, seed_mix: u32) -> f64 {
        match &self.size {
            Some(e) => eval(e, &Self::inputs(p, seed_mix)).s().max(0.0),
            None => 1.0,
        }
    }
}
