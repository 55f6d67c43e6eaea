//! Random effect files for the fuzz and differential tests, written as RON text.
//!
//! Two flavours share one grammar (every section and variant of the format):
//! - [`Flavor::Wild`]: structurally valid files whose numbers come from a mix of edge values
//!   (0, -0, ±1e30, 1e-30, f64::MAX, NaN, ±inf, u32::MAX ...) and ordinary ones. The compiler must
//!   reject them with diagnostics or accept them with naga-valid WGSL, and never panic.
//! - [`Flavor::Tame`]: valid, moderate effects (small capacity, gentle forces, no planes or kill
//!   volumes, whose decisions within f32 rounding are known to split GPU from CPU) for the GPU
//!   vs CPU-reference comparison.
//! - [`Flavor::Valid`]: the tame numbers with every feature (planes, kill volumes, Exact).
#![allow(dead_code)]

use proptest::prelude::*;

/// Which kind of numbers to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Flavor {
    /// Anything, edge values included.
    Wild,
    /// Valid and moderate numbers, every feature.
    Valid,
    /// Valid and moderate, without planes, kill volumes or Exact.
    Tame,
}

/// An f64 as RON writes it (`NaN`, `inf` and `-inf` included).
fn ron_f64(x: f64) -> String {
    if x.is_nan() {
        "NaN".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

/// Mostly the tame range (so that many files get deep into the compiler), sometimes any
/// ordinary number, sometimes an edge value.
fn wild_f64(lo: f64, hi: f64) -> BoxedStrategy<f64> {
    prop_oneof![
        12 => lo..hi,
        3 => -10.0..10.0f64,
        1 => -1e4..1e4f64,
        1 => prop::sample::select(vec![
            0.0, -0.0, 1.0, -1.0, 0.5, 1e30, -1e30, 1e-30, -1e-30, 1e-300, f64::MAX, f64::MIN,
            f64::MIN_POSITIVE, f64::EPSILON, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 3.4e38,
            3.5e38, 1e-45, 16777217.0, 1e6, 256.0,
        ]),
    ]
    .boxed()
}

fn num(flavor: Flavor, lo: f64, hi: f64) -> BoxedStrategy<String> {
    match flavor {
        Flavor::Wild => wild_f64(lo, hi).prop_map(ron_f64).boxed(),
        Flavor::Valid | Flavor::Tame => (lo..hi).prop_map(ron_f64).boxed(),
    }
}

fn count(flavor: Flavor, lo: u32, hi: u32) -> BoxedStrategy<u32> {
    match flavor {
        Flavor::Wild => prop_oneof![
            8 => lo..=hi,
            2 => 0u32..300,
            1 => prop::sample::select(vec![0, 1, 255, 256, 257, 65_535, 1 << 20, 1 << 31, u32::MAX]),
        ]
        .boxed(),
        Flavor::Valid | Flavor::Tame => (lo..=hi).boxed(),
    }
}

fn vec3(flavor: Flavor, lo: f64, hi: f64) -> BoxedStrategy<String> {
    (
        num(flavor, lo, hi),
        num(flavor, lo, hi),
        num(flavor, lo, hi),
    )
        .prop_map(|(x, y, z)| format!("({x}, {y}, {z})"))
        .boxed()
}

/// A direction: never near zero in the tame flavour.
fn direction(flavor: Flavor) -> BoxedStrategy<String> {
    match flavor {
        Flavor::Wild => vec3(flavor, -1.0, 1.0),
        Flavor::Valid | Flavor::Tame => (0.3..1.0f64, -1.0..1.0f64, -1.0..1.0f64, any::<bool>())
            .prop_map(|(a, b, c, flip)| {
                let a = if flip { -a } else { a };
                format!("({}, {}, {})", ron_f64(b), ron_f64(a), ron_f64(c))
            })
            .boxed(),
    }
}

fn range(flavor: Flavor, lo: f64, hi: f64) -> BoxedStrategy<String> {
    match flavor {
        Flavor::Wild => (num(flavor, lo, hi), num(flavor, lo, hi))
            .prop_map(|(a, b)| format!("({a}, {b})"))
            .boxed(),
        Flavor::Valid | Flavor::Tame => (lo..hi, lo..hi)
            .prop_map(|(a, b)| format!("({}, {})", ron_f64(a.min(b)), ron_f64(a.max(b))))
            .boxed(),
    }
}

fn shape(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    prop_oneof![
        vec3(f, -2.0, 2.0).prop_map(|p| format!("Point({p})")),
        (vec3(f, -2.0, 2.0), num(f, 0.01, 1.0), any::<bool>()).prop_map(|(c, r, on)| format!(
            "Sphere(center: {c}, radius: {r}, surface: {on})"
        )),
        (vec3(f, -2.0, -0.5), vec3(f, 0.5, 2.0), any::<bool>())
            .prop_map(|(a, b, on)| format!("Box(min: {a}, max: {b}, surface: {on})")),
        (vec3(f, -2.0, 2.0), direction(f), num(f, 0.01, 1.0))
            .prop_map(|(c, n, r)| format!("Disc(center: {c}, normal: {n}, radius: {r})")),
        (vec3(f, -2.0, 2.0), direction(f), num(f, 0.01, 1.0))
            .prop_map(|(c, n, r)| format!("Circle(center: {c}, normal: {n}, radius: {r})")),
        (
            vec3(f, -2.0, 2.0),
            direction(f),
            num(f, 0.0, 2.0),
            num(f, 0.0, 1.0),
            num(f, 0.0, 1.0),
            any::<bool>()
        )
            .prop_map(|(b, a, h, r0, r1, on)| format!(
                "Cone(base: {b}, axis: {a}, height: {h}, base_radius: {r0}, top_radius: {r1}, surface: {on})"
            )),
        (vec3(f, -2.0, 2.0), direction(f), num(f, 0.5, 2.0), num(f, 0.0, 0.45), any::<bool>())
            .prop_map(|(c, a, r, t, on)| format!(
                "Torus(center: {c}, axis: {a}, radius: {r}, tube: {t}, surface: {on})"
            )),
        (
            vec3(f, -2.0, -0.5),
            vec3(f, 0.5, 2.0),
            count(f, 1, 3),
            count(f, 1, 3),
            count(f, 1, 3)
        )
            .prop_map(|(a, b, x, y, z)| format!(
                "Grid(min: {a}, max: {b}, counts: ({x}, {y}, {z}))"
            )),
        prop::collection::vec(vec3(f, -2.0, 2.0), usize::from(f != Flavor::Wild)..4)
            .prop_map(|ps| format!("Points([{}])", ps.join(", "))),
        spawn_expression(f, false).prop_map(|e| format!("Custom(\"{e}\")")),
    ]
    .boxed()
}

/// A spawn position (`velocity` false) or velocity written as an expression: smooth and
/// bounded in the valid flavours, of the names each may read (a velocity also reads `x`);
/// wild ones also name what spawn expressions may not read.
fn spawn_expression(flavor: Flavor, velocity: bool) -> BoxedStrategy<String> {
    let f = flavor;
    let mut names = vec!["t", "dt", "rand(0)", "rand(7)"];
    if velocity {
        names.extend(["x.x", "x.y", "length(x)"]);
    }
    if f == Flavor::Wild {
        names.extend(["v.x", "age", "life", "x.z", "rand(300)"]);
    }
    let scalar = || {
        prop_oneof![
            num(f, -2.0, 2.0),
            prop::sample::select(names.clone()).prop_map(str::to_string),
        ]
    };
    (scalar(), scalar(), scalar(), num(f, 0.1, 2.0))
        .prop_map(|(a, b, c, s)| format!("vec3(sin({a}), cos({b}), sin({c})) * {s}"))
        .boxed()
}

fn velocity(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    prop_oneof![
        vec3(f, -3.0, 3.0).prop_map(|v| format!("Constant({v})")),
        (direction(f), num(f, 0.0, 60.0), range(f, 0.0, 4.0))
            .prop_map(|(a, ang, s)| format!("Cone(axis: {a}, angle: {ang}, speed: {s})")),
        range(f, 0.0, 4.0).prop_map(|s| format!("Radial(speed: {s})")),
        (direction(f), range(f, -4.0, 4.0))
            .prop_map(|(a, s)| format!("Tangent(axis: {a}, speed: {s})")),
        spawn_expression(f, true).prop_map(|e| format!("Custom(\"{e}\")")),
    ]
    .boxed()
}

fn emitter(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    let lifetime = prop_oneof![
        Just(String::new()),
        range(f, 0.5, 3.0).prop_map(|r| format!(", lifetime: Some({r})")),
    ];
    // When it spawns: mostly from step 0 for ever, sometimes late, for a while, or in
    // repeating bursts (every >= 0.05 s, above the generated effects' largest dt).
    let timing = prop_oneof![
        3 => Just(String::new()),
        1 => (num(f, 0.0, 0.5), prop::option::of(num(f, 0.05, 1.0))).prop_map(|(start, d)| {
            let d = d.map_or(String::new(), |d| format!(", duration: Some({d})"));
            format!(", start: {start}{d}")
        }),
        1 => (num(f, 0.05, 0.6), prop::option::of(count(f, 1, 5))).prop_map(|(every, n)| {
            let n = n.map_or(String::new(), |n| format!(", cycles: Some({n})"));
            format!(", every: Some({every}){n}")
        }),
        // Gaps drawn anew for each repeat.
        1 => (num(f, 0.05, 0.3), num(f, 0.3, 0.9)).prop_map(|(lo, hi)| {
            format!(", every: Some(({lo}, {hi}))")
        }),
    ];
    // A burst count drawn anew for each burst, sometimes; a starting age, sometimes.
    let burst = prop_oneof![
        3 => count(f, 1, 24).prop_map(|n| n.to_string()),
        1 => (count(f, 1, 24), count(f, 0, 24)).prop_map(|(lo, more)| format!("({lo}, {})", lo.saturating_add(more))),
    ];
    let age = prop_oneof![
        3 => Just(String::new()),
        1 => range(f, 0.0, 0.5).prop_map(|r| format!(", age: Some({r})")),
    ];
    (
        burst,
        num(f, 0.0, 60.0),
        shape(f),
        velocity(f),
        lifetime,
        timing,
        age,
    )
        .prop_map(|(burst, rate, shape, vel, life, timing, age)| {
            format!("Emitter(burst: {burst}, rate: {rate}, shape: {shape}, velocity: {vel}{life}{timing}{age})")
        })
        .boxed()
}

fn force(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    prop_oneof![
        vec3(f, -3.0, 3.0).prop_map(|g| format!("Gravity({g})")),
        (num(f, 0.0, 2.0), vec3(f, -1.0, 1.0))
            .prop_map(|(k, fl)| format!("Drag(k: {k}, fluid: {fl})")),
        (
            direction(f),
            num(f, 0.0, 2.0),
            num(f, 0.0, 1.0),
            num(f, 0.5, 4.0)
        )
            .prop_map(|(d, s, n, sc)| format!(
                "Wind(direction: {d}, strength: {s}, noise: {n}, noise_scale: {sc})"
            )),
        (vec3(f, -2.0, 2.0), num(f, 2.0, 6.0), num(f, -1.0, 2.0), any::<bool>()).prop_map(
            |(c, r, s, core)| {
                let core = if core { ", core: 1.0" } else { "" };
                format!("Attractor(center: {c}, range: {r}, strength: {s}{core})")
            }
        ),
        (
            vec3(f, -1.0, 1.0),
            direction(f),
            num(f, 1.5, 4.0),
            num(f, 1.0, 6.0),
            (num(f, -2.0, 2.0), num(f, -1.0, 1.0), num(f, -1.0, 1.0), num(f, 0.0, 2.0))
        )
            .prop_map(|(c, a, r, h, (spin, pull, down, curve))| format!(
                "Vortex(center: {c}, axis: {a}, range: {r}, height: {h}, spin: {spin}, pull: {pull}, down: {down}, curve: {curve})"
            )),
        (
            num(f, 0.2, 1.0),
            (num(f, 0.0, 2.0), num(f, 0.0, 1.0), num(f, 0.0, 0.5), num(f, 0.0, 0.5)),
            prop::sample::select(vec!["Global", "Local"]),
            prop_oneof![Just(None), num(f, 1.0, 2.0).prop_map(Some)],
        )
            .prop_map(|(r, (sep, avoid, coh, ali), scope, cell)| {
                let neighbors = match cell {
                    Some(c) => format!("Grid(cell: {c})"),
                    None => String::from("AllPairs"),
                };
                format!(
                    "Flock(radius: {r}, separation: {sep}, avoidance: {avoid}, cohesion: {coh}, alignment: {ali}, scope: {scope}, neighbors: {neighbors})"
                )
            }),
        custom_force(f),
    ]
    .boxed()
}

/// A random expression of type f32 (`vector` false) or vec3, `depth` levels deep. Wild
/// expressions use every function and operator, edge constants and the particle context; tame
/// ones only smooth functions of bounded size (the differential test compares GPU and CPU, and a
/// step or floor could split them at a boundary within f32 rounding).
pub fn expression(flavor: Flavor, vector: bool, depth: u32) -> BoxedStrategy<String> {
    let f = flavor;
    let leaf = if vector {
        prop_oneof![
            Just("x".to_string()),
            Just("v".to_string()),
            (num(f, -2.0, 2.0), num(f, -2.0, 2.0), num(f, -2.0, 2.0))
                .prop_map(|(a, b, c)| format!("vec3({a}, {b}, {c})")),
        ]
        .boxed()
    } else {
        let names = if f == Flavor::Wild {
            vec![
                "x.x",
                "v.y",
                "x.z",
                "t",
                "age",
                "life",
                "dt",
                "rand(0)",
                "rand(255)",
                "k",
            ]
        } else {
            vec!["x.x", "x.y", "v.z", "t", "k"]
        };
        prop_oneof![
            num(f, -2.0, 2.0),
            prop::sample::select(names).prop_map(str::to_string),
        ]
        .boxed()
    };
    if depth == 0 {
        return leaf;
    }
    let s = || expression(f, false, depth - 1);
    let v = || expression(f, true, depth - 1);
    if f != Flavor::Wild {
        // Smooth and bounded: sums and products of sines of smooth trees.
        return if vector {
            prop_oneof![
                leaf,
                (s(), s(), s()).prop_map(|(a, b, c)| format!("vec3(sin({a}), cos({b}), sin({c}))")),
                (v(), s()).prop_map(|(a, b)| format!("0.5 * (sin({b}) * normalize({a}))")),
                (v(), v()).prop_map(|(a, b)| format!(
                    "0.1 * cross(sin({a}.x) * {b}, vec3(0.0, 1.0, 0.0))"
                )),
            ]
            .boxed()
        } else {
            prop_oneof![
                leaf,
                (s(), s()).prop_map(|(a, b)| format!("({a} + {b})")),
                (s(), s()).prop_map(|(a, b)| format!("sin({a}) * cos({b})")),
                (v(), v())
                    .prop_map(|(a, b)| format!("0.1 * dot(sin({a}.x) * {b}, vec3(1.0, 0.0, 0.0))")),
            ]
            .boxed()
        };
    }
    let unary = prop::sample::select(vec![
        "-", "abs", "floor", "fract", "sqrt", "exp", "log", "sin", "cos", "ceil", "round", "sign",
        "tan", "asin", "acos", "atan", "log2",
    ]);
    let binary = prop::sample::select(vec![
        "+", "-", "*", "/", "min", "max", "pow", "atan2", "step", "rem",
    ]);
    let ternary = prop::sample::select(vec!["clamp", "mix", "smoothstep"]);
    let compare = prop::sample::select(vec!["<", "<=", ">", ">=", "==", "!="]);
    let call2 = |op: &str, a: String, b: String| match op {
        "+" | "-" | "*" | "/" => format!("({a} {op} {b})"),
        _ => format!("{op}({a}, {b})"),
    };
    let same = move |vector: bool| {
        if vector {
            expression(f, true, depth - 1)
        } else {
            expression(f, false, depth - 1)
        }
    };
    let mut options: Vec<BoxedStrategy<String>> = vec![
        leaf,
        (unary, same(vector))
            .prop_map(|(op, a)| format!("{op}({a})"))
            .boxed(),
        (binary, same(vector), same(vector))
            .prop_map(move |(op, a, b)| call2(op, a, b))
            .boxed(),
        (ternary, same(vector), same(vector), same(vector))
            .prop_map(|(op, a, b, c)| format!("{op}({a}, {b}, {c})"))
            .boxed(),
        (same(vector), same(vector), compare, s(), s())
            .prop_map(|(a, b, op, l, r)| format!("select({a}, {b}, {l} {op} {r})"))
            .boxed(),
    ];
    if vector {
        options.push(
            (s(), s(), s())
                .prop_map(|(a, b, c)| format!("vec3({a}, {b}, {c})"))
                .boxed(),
        );
        options.push(
            (v(), v())
                .prop_map(|(a, b)| format!("cross({a}, {b})"))
                .boxed(),
        );
        options.push(v().prop_map(|a| format!("normalize({a})")).boxed());
        options.push((s(), v()).prop_map(|(a, b)| format!("({a} * {b})")).boxed());
    } else {
        options.push(
            (v(), v())
                .prop_map(|(a, b)| format!("dot({a}, {b})"))
                .boxed(),
        );
        options.push(v().prop_map(|a| format!("length({a})")).boxed());
        options.push(v().prop_map(|a| format!("{a}.y")).boxed());
    }
    proptest::strategy::Union::new(options).boxed()
}

/// A Custom force: a vec3 expression (tame ones scaled to stay gentle).
fn custom_force(flavor: Flavor) -> BoxedStrategy<String> {
    let depth = if flavor == Flavor::Wild { 3 } else { 2 };
    expression(flavor, true, depth)
        .prop_map(move |e| {
            let e = if flavor == Flavor::Wild {
                e
            } else {
                format!("0.5 * sin({e})")
            };
            format!("Custom(accel: \"{e}\")")
        })
        .boxed()
}

fn plane(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    (
        vec3(f, -3.0, -1.0),
        direction(f),
        num(f, 0.0, 1.0),
        num(f, 0.0, 1.0),
        0..5u32,
        num(f, 0.1, 3.0),
        num(f, -1.0, 2.0),
    )
        .prop_map(|(p, n, r, fr, kind, size, h)| match kind {
            // Mostly planes; the other colliders built from the same numbers.
            0 => format!(
                "Sphere(center: {p}, radius: {size}, restitution: {r}, friction: {fr}, inside: false)"
            ),
            1 => format!(
                "Box(min: (-3.0, -3.0, -3.0), max: (3.0, {size}, 3.0), restitution: {r}, friction: {fr}, inside: true)"
            ),
            2 => format!(
                "HeightField(min: (-4.0, -4.0), max: (4.0, 4.0), heights: [[{h}, 0.0, -1.0], [0.5, {h}, 0.0]], restitution: {r}, friction: {fr})"
            ),
            _ => format!("Plane(point: {p}, normal: {n}, restitution: {r}, friction: {fr})"),
        })
        .boxed()
}

fn kill(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    prop_oneof![
        (vec3(f, -9.0, -8.0), vec3(f, 8.0, 9.0))
            .prop_map(|(a, b)| format!("InsideBox(min: {a}, max: {b})")),
        (vec3(f, -9.0, -8.0), vec3(f, 8.0, 9.0))
            .prop_map(|(a, b)| format!("OutsideBox(min: {a}, max: {b})")),
        (vec3(f, -1.0, 1.0), num(f, 0.1, 1.0))
            .prop_map(|(c, r)| format!("InsideSphere(center: {c}, radius: {r})")),
        (vec3(f, -1.0, 1.0), num(f, 20.0, 30.0))
            .prop_map(|(c, r)| format!("OutsideSphere(center: {c}, radius: {r})")),
    ]
    .boxed()
}

fn render(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    // Tame stops sit at t = 0, 0.5, 1 in order; wild ones anywhere.
    let at = move |i: usize| match f {
        Flavor::Valid | Flavor::Tame => Just(ron_f64(i as f64 * 0.5)).boxed(),
        Flavor::Wild => num(f, 0.0, 1.0),
    };
    let stop = move |i: usize| {
        (at(i), vec3(f, 0.0, 1.0), num(f, 0.0, 1.0)).prop_map(|(t, c, a)| {
            let c = c.trim_start_matches('(').trim_end_matches(')').to_string();
            format!("({t}, ({c}, {a}))")
        })
    };
    let size = move |i: usize| (at(i), num(f, 0.01, 0.3)).prop_map(|(t, s)| format!("({t}, {s})"));
    let min = usize::from(f != Flavor::Wild);
    let stops = (min..3usize).prop_flat_map(move |n| (0..n).map(stop).collect::<Vec<_>>());
    let sizes = (min..3usize).prop_flat_map(move |n| (0..n).map(size).collect::<Vec<_>>());
    // Orientation: the default, streaks along the velocity, or a fixed plane.
    let orient = prop_oneof![
        Just("Camera".to_string()),
        (num(f, 0.0, 0.2), num(f, 0.01, 2.0))
            .prop_map(|(s, m)| format!("Velocity(stretch: {s}, max_length: {m})")),
        vec3(f, 0.1, 1.0).prop_map(|n| format!("Fixed({n})")),
    ];
    // Texture: none, one image, or the bird atlas (4 x 1 frames, relative to the tests' working
    // directory, the repository) over life or at a rate, with or without a random start.
    let texture = prop_oneof![
        Just("None".to_string()),
        Just(r#"Some(Texture(file: "effects/textures/snowflake.png"))"#.to_string()),
        Just(r#"Some(Texture(file: "effects/textures/bird.png", frames: (4, 1)))"#.to_string()),
        (num(f, 0.5, 60.0), any::<bool>()).prop_map(|(fps, random)| format!(
            r#"Some(Texture(file: "effects/textures/bird.png", frames: (4, 1), play: Rate({fps}), random_start: {random}))"#
        )),
    ];
    // Rotation: none, or a starting angle and a spin (kept off velocity-aligned sprites, which
    // refuse it).
    let rotation = prop_oneof![
        Just(None),
        (
            num(f, -360.0, 0.0),
            num(f, 0.0, 360.0),
            num(f, -720.0, 0.0),
            num(f, 0.0, 720.0)
        )
            .prop_map(|(a0, a1, s0, s1)| Some(format!(
                "Some(Rotation(angle: ({a0}, {a1}), spin: ({s0}, {s1})))"
            ))),
    ];
    // Trail: none, or a ribbon of 2 to 64 points with its own width and colour stops.
    let widths = (1..3usize).prop_flat_map(move |n| (0..n).map(size).collect::<Vec<_>>());
    let tints = (1..3usize).prop_flat_map(move |n| (0..n).map(stop).collect::<Vec<_>>());
    // A height and an alpha curve of their own, or none.
    let heights =
        prop::option::of((1..3usize).prop_flat_map(move |n| (0..n).map(size).collect::<Vec<_>>()));
    let alphas = prop::option::of((1..3usize).prop_flat_map(move |n| {
        (0..n)
            .map(|i| (at(i), num(f, 0.0, 1.0)).prop_map(|(t, a)| format!("({t}, {a})")))
            .collect::<Vec<_>>()
    }));
    // A palette of 1 to 4 colours, or none (wild: out of range or empty).
    let palette = prop::option::of(
        (usize::from(f != Flavor::Wild)..5usize)
            .prop_flat_map(move |n| (0..n).map(|_| vec3(f, 0.0, 1.0)).collect::<Vec<_>>()),
    )
    .prop_map(|p| p.map_or("None".to_string(), |c| format!("Some([{}])", c.join(", "))));
    let trail =
        prop::option::of((count(f, 2, 64), count(f, 1, 5), widths, tints)).prop_map(|t| match t {
            None => "None".to_string(),
            Some((points, every, w, c)) => format!(
                "Some(Trail(points: {points}, every: {every}, width: [{}], color: [{}]))",
                w.join(", "),
                c.join(", ")
            ),
        });
    // Lit by the lights (flat or sphere normals, a wrap and an emissive part), and the light the
    // brightest particles give off; or neither.
    let lit =
        prop::option::of((any::<bool>(), num(f, 0.0, 1.0), num(f, 0.0, 1.0))).prop_map(
            |l| match l {
                None => "None".to_string(),
                Some((flat, wrap, emissive)) => format!(
                    "Some(Lit(normals: {}, wrap: {wrap}, emissive: {emissive}))",
                    if flat { "Flat" } else { "Sphere" }
                ),
            },
        );
    let light = prop::option::of((count(f, 1, 8), num(f, 0.0, 3.0), num(f, 0.1, 10.0))).prop_map(
        |l| match l {
            None => "None".to_string(),
            Some((n, intensity, range)) => {
                format!("Some(ParticleLight(count: {n}, intensity: {intensity}, range: {range}))")
            }
        },
    );
    // What a texel does; a frame by expression (on the atlas); and the group drawn as ribbons
    // (`Wild` only: they refuse trails, textures and a depth sort, which the other flavours
    // would have accepted; the render fields they refuse are then left out).
    let sample = prop::sample::select(vec!["Modulate", "ModulateRgb", "OpacityFromRed"]);
    let ribbon = prop::option::of((
        count(f, 2, 256),
        count(f, 1, 64),
        prop::option::of(count(f, 1, 50)),
    ))
    .prop_map(move |r| match r {
        Some((points, rows, split)) if f == Flavor::Wild => Some(format!(
            "Some(Ribbon(points: {points}, ribbons: {rows}, split: {}))",
            split.map_or("None".to_string(), |n| format!("Some({n})"))
        )),
        _ => None,
    });
    let extra = (sample, any::<bool>(), ribbon);
    (
        stops,
        sizes,
        prop_oneof![
            prop::sample::select(vec!["Alpha", "Additive", "Multiply", "Premultiplied", "Opaque"])
                .prop_map(str::to_string),
            num(f, 0.0, 1.0).prop_map(|c| format!("Mask({c})")),
        ],
        vec3(f, 0.0, 1.0),
        orient,
        (
            texture,
            rotation,
            prop::option::of(num(f, 0.01, 2.0)),
            prop::option::of((num(f, 0.0, 2.0), num(f, 0.0, 3.0), num(f, 0.001, 0.05))),
            trail,
            heights,
            alphas,
            palette,
        ),
        (lit, light, extra),
    )
        .prop_map(|(c, s, b, bg, o, (t, r, soft, glow, trail, heights, alphas, palette), (lit, light, (sample, by_frame, ribbon)))| {
            let list = |stops: Option<Vec<String>>| {
                stops.map_or("None".to_string(), |s| format!("Some([{}])", s.join(", ")))
            };
            let (heights, alphas) = (list(heights), list(alphas));
            let soft = soft.map_or("None".to_string(), |d| format!("Some({d})"));
            let glow = glow.map_or("None".to_string(), |(t, s, r)| {
                format!("Some(Glow(threshold: {t}, strength: {s}, radius: {r}))")
            });
            let r = match r {
                Some(r) if !o.starts_with("Velocity") => r,
                _ => "None".to_string(),
            };
            // The texture's sample mapping, and on the atlas a frame from the age and time.
            let frame_by = match by_frame && t.contains("frames") {
                true => r#"Some("age * 4.0 + t")"#,
                false => "None",
            };
            let t = match t.as_str() {
                "None" => t,
                _ => format!("{}, sample: {sample}))", t.trim_end_matches("))")),
            };
            let looks = match ribbon {
                // A ribbon draws no trail, texture, turned sprite or height (and the lit looks
                // made here have no maps, which would need a texture).
                Some(ribbon) => format!(
                    "orient: Camera, texture: None, rotation: None, soft: {soft}, glow: {glow}, trail: None, size_y: None, alpha: {alphas}, palette: {palette}, lit: {lit}, light: {light}, ribbon: {ribbon}"
                ),
                None => format!(
                    "orient: {o}, texture: {t}, rotation: {r}, soft: {soft}, glow: {glow}, trail: {trail}, size_y: {heights}, alpha: {alphas}, palette: {palette}, lit: {lit}, light: {light}, frame_by: {frame_by}"
                ),
            };
            format!(
                "render: Render(color: [{}], size: [{}], blend: {b}, background: {bg}, {looks}),",
                c.join(", "),
                s.join(", ")
            )
        })
        .boxed()
}

/// A baked field over [-3, 3]³. Tame fields are trilinear (nearest jumps between nodes where f32
/// and f64 round differently) and baked every step (valid with noise too).
fn field(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    let filters = if f == Flavor::Tame {
        vec!["Trilinear"]
    } else {
        vec!["Trilinear", "Nearest"]
    };
    let refresh = if f == Flavor::Tame {
        vec!["EveryStep"]
    } else {
        vec!["EveryStep", "Once"]
    };
    (
        (count(f, 2, 12), count(f, 2, 12), count(f, 2, 12)),
        vec3(f, -3.0, -2.5),
        vec3(f, 2.5, 3.0),
        prop::sample::select(filters),
        prop::sample::select(refresh),
    )
        .prop_map(|((nx, ny, nz), min, max, filter, refresh)| {
            format!(
                "field: Baked(resolution: ({nx}, {ny}, {nz}), min: {min}, max: {max}, filter: {filter}, refresh: {refresh}),"
            )
        })
        .boxed()
}

/// The integrator names of the format (Auto included).
pub const INTEGRATORS: &[&str] = &[
    "Auto",
    "Euler",
    "SemiImplicitEuler",
    "Verlet",
    "Midpoint",
    "Rk4",
    "Exact",
];

/// A whole effect file.
pub fn effect(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    let tame = f == Flavor::Tame;
    let integrators: Vec<&'static str> = if tame {
        // Exact is only allowed for some force mixes; Auto covers it where it is.
        INTEGRATORS
            .iter()
            .copied()
            .filter(|i| *i != "Exact")
            .collect()
    } else {
        INTEGRATORS.to_vec()
    };
    let planes = if tame { 0..1usize } else { 0..3 };
    let kills = if tame { 0..1usize } else { 0..3 };
    (
        (
            count(f, 8, 64),
            any::<u32>(),
            num(f, 0.005, 0.034),
            count(f, 1, 3),
            num(f, -1.0, 1.0),
        ),
        prop::collection::vec(emitter(f), if tame { 1..3 } else { 0..3 }),
        (prop::collection::vec(force(f), 0..5), attributes(f)),
        prop::collection::vec(plane(f), planes),
        prop::collection::vec(kill(f), kills),
        (
            prop::sample::select(integrators),
            prop_oneof![Just(String::new()), num(f, 5.0, 50.0).prop_map(|s| format!("max_speed: Some({s}),"))],
            any::<bool>(),
            prop_oneof![Just(String::new()), render(f)],
            prop_oneof![Just(String::new()), field(f)],
            // Tame effects must compile, so they never demand Stateless.
            if tame {
                prop::sample::select(vec!["", "state: Stateful,"])
            } else {
                prop::sample::select(vec!["", "state: Stateful,", "state: Stateless,"])
            },
        ),
    )
        .prop_map(
            move |((cap, seed, dt, substeps, k), emitters, (mut forces, (attributes, reader)), planes, kills, (integ, max_speed, sort, render, field, state))| {
                forces.extend(reader);
                if f != Flavor::Wild {
                    // An effect has at most one Flock.
                    let mut flocks = 0;
                    forces.retain(|force| !force.starts_with("Flock") || {
                        flocks += 1;
                        flocks == 1
                    });
                }
                format!(
                    "Effect(\n    name: \"fuzz\",\n    capacity: {cap},\n    seed: {seed},\n    dt: {dt},\n    substeps: {substeps},\n    params: {{\"k\": {k}, \"w\": ({k}, 0.5, -0.25)}},\n    {attributes}\n    emitters: [{}],\n    forces: [{}],\n    collide: [{}],\n    kill: [{}],\n    integrator: {integ},\n    {max_speed}\n    sort: {sort},\n    {state}\n    {render}\n    {field}\n)\n",
                    emitters.join(",\n        "),
                    forces.join(",\n        "),
                    planes.join(", "),
                    kills.join(", "),
                )
            },
        )
        .boxed()
}

/// Attributes and a named expression, and a custom force that reads them, sometimes: (the
/// fields' text, the forces to add).
fn attributes(flavor: Flavor) -> BoxedStrategy<(String, Vec<String>)> {
    let f = flavor;
    let scalar = || expression(f, false, 2);
    let vector = || expression(f, true, 2);
    prop_oneof![
        2 => Just((String::new(), Vec::new())),
        1 => (scalar(), scalar(), vector(), vector(), scalar(), any::<bool>()).prop_map(
            |(spawn_a, change_a, spawn_b, change_b, define, rate)| {
                let change = match rate {
                    true => format!("rate: Some(\"{change_a} - a\")"),
                    false => format!("update: Some(\"a * 0.5 + {change_a}\")"),
                };
                (
                    format!(
                        "define: {{\"d\": \"{define}\"}},\n    attributes: {{\"a\": (spawn: \"{spawn_a}\", {change}), \"b\": (spawn: \"{spawn_b}\", update: Some(\"{change_b} * 0.5 + w\"))}},"
                    ),
                    vec!["Custom(accel: \"(b - w) * 0.1 + vec3(0.0, a * 0.01, d * 0.01)\")".to_string()],
                )
            }
        ),
    ]
    .boxed()
}

/// An event: a trigger, a target among `targets` (or, wild, any name), a count and a spawn
/// rule.
fn event(flavor: Flavor, targets: Vec<&'static str>) -> BoxedStrategy<String> {
    let f = flavor;
    let on = prop_oneof![
        Just("Death".to_string()),
        Just("Collide".to_string()),
        num(f, 0.005, 0.5).prop_map(|s| format!("Every({s})")),
    ];
    (
        on,
        prop::sample::select(targets),
        count(f, 1, 8),
        shape(f),
        velocity(f),
        range(f, 0.05, 1.0),
        num(f, 0.0, 1.0),
        any::<bool>(),
    )
        .prop_map(|(on, target, count, shape, vel, life, inherit, colour)| {
            format!(
                "Event(on: {on}, target: \"{target}\", count: {count}, shape: {shape}, velocity: {vel}, lifetime: Some({life}), inherit_velocity: {inherit}, inherit_color: {colour})"
            )
        })
        .boxed()
}

/// A group fed by events (no emitters of its own), with forces, colliders, kill volumes and
/// events of its own aimed at `targets`.
fn group(flavor: Flavor, name: &'static str, targets: Vec<&'static str>) -> BoxedStrategy<String> {
    let events = if targets.is_empty() {
        Just(Vec::new()).boxed()
    } else {
        prop::collection::vec(event(flavor, targets), 0..2).boxed()
    };
    let f = flavor;
    let tame = f == Flavor::Tame;
    let integrators: Vec<&'static str> = INTEGRATORS
        .iter()
        .copied()
        .filter(|i| !tame || *i != "Exact")
        .collect();
    (
        count(f, 8, 300),
        prop::collection::vec(force(f), 0..3),
        prop::collection::vec(plane(f), 0..2),
        prop::collection::vec(kill(f), 0..2),
        prop::sample::select(integrators),
        prop_oneof![Just(String::new()), render(f)],
        events,
    )
        .prop_map(move |(cap, forces, planes, kills, integ, render, events)| {
            let forces: Vec<String> = forces
                .into_iter()
                .filter(|force| !(tame && force.starts_with("Flock")))
                .collect();
            format!(
                "Group(name: \"{name}\", capacity: {cap}, forces: [{}], collide: [{}], kill: [{}], integrator: {integ}, {render} events: [{}])",
                forces.join(", "),
                planes.join(", "),
                kills.join(", "),
                events.join(", ")
            )
        })
        .boxed()
}

/// An effect with groups and events: `effect`'s top level firing into two more groups (the
/// second fed by the first). Wild ones also aim at unknown groups, themselves and back up
/// the chain (loops the compiler must refuse).
pub fn graph_effect(flavor: Flavor) -> BoxedStrategy<String> {
    let f = flavor;
    let (top, middle, last): (Vec<&'static str>, Vec<&'static str>, Vec<&'static str>) =
        if f == Flavor::Wild {
            let all = vec!["fuzz", "a", "b", "nowhere"];
            (all.clone(), all.clone(), all)
        } else {
            (vec!["a"], vec!["b"], Vec::new())
        };
    (
        effect(f),
        prop::collection::vec(event(f, top), 1..3),
        group(f, "a", middle),
        group(f, "b", last),
    )
        .prop_map(move |(effect, events, a, b)| {
            let body = effect.trim_end().trim_end_matches(')');
            format!(
                "{body}\n    events: [{}],\n    groups: [{a}, {b}],\n)\n",
                events.join(", ")
            )
        })
        .boxed()
}

/// A random effect the stateless kernel must run (`state: Stateless`): one to three emitters,
/// each mortal or a burst that never dies, under gravity, drag and wind (the closed form's
/// forces), with room for every spawn.
pub fn stateless_effect() -> BoxedStrategy<String> {
    let f = Flavor::Tame;
    let emitter = (
        count(f, 0, 40),
        prop_oneof![Just("0.0".to_string()), num(f, 1.0, 300.0)],
        shape(f),
        velocity(f),
        range(f, 0.05, 2.0),
        any::<bool>(),
        // Late, for a while, or a burst repeated a few times (every >= dt, below 0.05 s).
        prop_oneof![
            2 => Just(String::new()),
            1 => (num(f, 0.0, 0.5), num(f, 0.05, 1.0))
                .prop_map(|(start, d)| format!(", start: {start}, duration: Some({d})")),
            1 => (num(f, 0.05, 0.6), count(f, 1, 5))
                .prop_map(|(every, n)| format!(", every: Some({every}), cycles: Some({n})")),
        ],
    )
        .prop_map(|(burst, rate, shape, vel, life, immortal, timing)| {
            // Only a burst may live forever: a stream that never dies outgrows any capacity.
            let life = if immortal && rate == "0.0" {
                String::new()
            } else {
                format!(", lifetime: Some({life})")
            };
            // A repeating burst needs a burst to repeat.
            let burst = if timing.contains("every") { burst.max(1) } else { burst };
            format!("Emitter(burst: {burst}, rate: {rate}, shape: {shape}, velocity: {vel}{life}{timing})")
        });
    (
        any::<u32>(),
        num(f, 0.005, 0.05),
        prop::collection::vec(emitter, 1..4),
        vec3(f, -12.0, 12.0),
        prop_oneof![Just(String::new()), num(f, 0.01, 4.0).prop_map(|k| format!(", Drag(k: {k})"))],
        prop_oneof![
            Just(String::new()),
            (direction(f), num(f, 0.1, 5.0))
                .prop_map(|(d, s)| format!(", Wind(direction: {d}, strength: {s})"))
        ],
    )
        .prop_map(|(seed, dt, emitters, g, drag, wind)| {
            format!(
                "Effect(\n    name: \"stateless fuzz\",\n    capacity: 100000,\n    seed: {seed},\n    dt: {dt},\n    emitters: [{}],\n    forces: [Gravity({g}){drag}{wind}],\n    state: Stateless,\n)\n",
                emitters.join(",\n        ")
            )
        })
        .boxed()
}

/// Applies byte-level edits (replace, insert, delete) at random offsets of `text`.
pub fn mutate(text: &str, edits: &[(usize, u8, u8)]) -> String {
    let mut bytes = text.as_bytes().to_vec();
    for &(at, op, byte) in edits {
        if bytes.is_empty() {
            bytes.push(byte);
            continue;
        }
        let at = at % bytes.len();
        match op % 3 {
            0 => bytes[at] = byte,
            1 => bytes.insert(at, byte),
            _ => {
                bytes.remove(at);
            }
        }
    }
    String::from_utf8_lossy(&bytes).into_owned()
}
