//! The expression language's vocabulary: its types, the variables it reads, its operations
//! and the names of its functions (for messages and the arity check).

use super::parse::BinOp;

/// The type of a value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ty {
    /// A number (f32 on the GPU, f64 in the reference).
    Scalar,
    /// Three numbers.
    Vec3,
    /// A comparison's result: only `select` takes it.
    Bool,
}

impl Ty {
    /// As written in messages.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Ty::Scalar => "f32",
            Ty::Vec3 => "vec3",
            Ty::Bool => "bool",
        }
    }
}

/// What an expression may read about the particle and the simulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Var {
    /// Position (m), vec3.
    X,
    /// Velocity (m/s), vec3.
    V,
    /// Simulation time (s).
    T,
    /// The particle's age (s).
    Age,
    /// The particle's lifetime (s); 0 for particles that never die.
    Life,
    /// The particle's index among its emitter's spawns (an event's children: among its
    /// firing's), as a number: spawn positions only.
    Index,
    /// Where the spawn's frame sits in the world: the firing particle's position for an
    /// event's spawn, (0, 0, 0) for an emitter's; spawn positions and velocities only.
    Origin,
}

impl Var {
    /// The name as written.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Var::X => "x",
            Var::V => "v",
            Var::T => "t",
            Var::Age => "age",
            Var::Life => "life",
            Var::Index => "index",
            Var::Origin => "origin",
        }
    }

    /// The type of its value.
    pub(crate) fn ty(self) -> Ty {
        match self {
            Var::X | Var::V | Var::Origin => Ty::Vec3,
            _ => Ty::Scalar,
        }
    }
}

/// Operations of one operand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Op1 {
    /// `-a`
    Neg,
    /// `abs`
    Abs,
    /// `floor`
    Floor,
    /// `fract`: a − floor(a).
    Fract,
    /// `ceil`
    Ceil,
    /// `round`: to the nearest whole number, halves to even (WGSL's rule).
    Round,
    /// `sign`: −1, 0 or 1.
    Sign,
    /// `tan`, within the value bound.
    Tan,
    /// `asin` of a clamped to [−1, 1].
    Asin,
    /// `acos` of a clamped to [−1, 1].
    Acos,
    /// `atan`
    Atan,
    /// `log2` of max(a, `LOG_FLOOR`).
    Log2,
    /// `sqrt` of max(a, 0).
    Sqrt,
    /// `exp`, its argument clamped so the result stays within the value bound.
    Exp,
    /// `log` of max(a, `LOG_FLOOR`).
    Log,
    /// `sin`
    Sin,
    /// `cos`
    Cos,
    /// `length` of a vec3.
    Length,
    /// `normalize`: zero for a vector too short to normalise.
    Normalize,
    /// Component `.x`, `.y` or `.z` (0, 1, 2).
    Component(u8),
    /// `noise(p)`: 3D gradient noise at p (unit cells), within about ±1.
    Noise,
    /// `curl(p)`: the curl of a potential of three gradient noises at p: divergence-free.
    Curl,
}

/// Operations of two operands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Op2 {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*` (a scalar scales a vec3; two vec3s multiply per component).
    Mul,
    /// `/`, zero where the divisor is within `DIV_FLOOR` of zero.
    Div,
    /// `min`
    Min,
    /// `max`
    Max,
    /// `pow(a, b)`: 0 for a <= 0.
    Pow,
    /// `atan2(y, x)`: 0 at (0, 0).
    Atan2,
    /// `rem(a, b)`: a − b · trunc(a / b), the remainder with a's sign; 0 where the divisor is
    /// within `DIV_FLOOR` of zero.
    Rem,
    /// `dot`
    Dot,
    /// `cross`
    Cross,
    /// `step(edge, a)`: 1 where a >= edge, else 0.
    Step,
    /// A comparison (`<` ...), giving a bool.
    Compare(BinOp),
}

/// Operations of three operands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Op3 {
    /// `vec3(a, b, c)`
    Vec3,
    /// `clamp(a, lo, hi)` = min(max(a, lo), hi).
    Clamp,
    /// `mix(a, b, s)` = a + (b − a) s.
    Mix,
    /// `smoothstep(e0, e1, a)`, 0 where e0 == e1.
    Smoothstep,
    /// `select(if_false, if_true, cond)`, as in WGSL.
    Select,
}

/// The variables of a particle as it steps (a custom force's, an attribute's change).
pub(crate) const VARIABLES: &[Var] = &[Var::X, Var::V, Var::T, Var::Age, Var::Life];

/// Every variable some expression reads: names a param, attribute or definition may not
/// take, and what a definition may read (checked again where it is read).
pub(crate) const EVERY_VARIABLE: &[Var] = &[
    Var::X,
    Var::V,
    Var::T,
    Var::Age,
    Var::Life,
    Var::Index,
    Var::Origin,
];

/// Functions and their arities, for messages and the arity check.
pub(crate) const FUNCTIONS: &[(&str, usize)] = &[
    ("vec3", 3),
    ("dot", 2),
    ("cross", 2),
    ("length", 1),
    ("normalize", 1),
    ("abs", 1),
    ("min", 2),
    ("max", 2),
    ("clamp", 3),
    ("mix", 3),
    ("step", 2),
    ("smoothstep", 3),
    ("sqrt", 1),
    ("exp", 1),
    ("log", 1),
    ("pow", 2),
    ("sin", 1),
    ("cos", 1),
    ("atan2", 2),
    ("noise", 1),
    ("curl", 1),
    ("floor", 1),
    ("fract", 1),
    ("ceil", 1),
    ("round", 1),
    ("sign", 1),
    ("tan", 1),
    ("asin", 1),
    ("acos", 1),
    ("atan", 1),
    ("log2", 1),
    ("rem", 2),
    ("select", 3),
    ("rand", 1),
    ("rand_sphere", 1),
    ("rand_ball", 1),
    ("rand_circle", 1),
    ("rand_disc", 1),
    ("rand_normal", 1),
    ("hsv", 3),
];

/// The largest `k` in `rand(k)`.
pub(crate) const MAX_RAND: u32 = 255;

/// The known name nearest `name` by edit distance, when it is near enough to be a slip (at
/// most a third of its letters changed, at least one).
pub(crate) fn closest<'n>(name: &str, known: impl Iterator<Item = &'n str>) -> Option<&'n str> {
    let most = (name.chars().count() / 3).max(1);
    known
        .map(|k| (edit_distance(name, k), k))
        .filter(|(d, _)| *d <= most)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// Edit distance in characters, a swap of two neighbours counting as one edit (the optimal
/// string alignment distance: `haet` is one edit from `heat`).
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}
