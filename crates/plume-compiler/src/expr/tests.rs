//! Unit tests of the expression language: located errors, guarded semantics, folding.

use std::collections::BTreeMap;

use glam::DVec3;

use super::eval::{eval, Inputs, Value};
use super::typed::{Node, Ty};
use super::{compile, ExprError};

fn params() -> BTreeMap<String, f64> {
    BTreeMap::from([("k".to_string(), 0.5)])
}

fn c(text: &str) -> Result<super::Expr, ExprError> {
    compile(text, Ty::Vec3, &params(), 0.01)
}

fn err(text: &str) -> (String, usize, usize) {
    let e = c(text).unwrap_err();
    (e.message, e.start, e.end)
}

fn at(text: &str, x: DVec3, v: DVec3) -> DVec3 {
    eval(
        &c(text).unwrap_or_else(|e| panic!("{text}: {}", e.message)),
        &Inputs {
            x,
            v,
            ..Inputs::default()
        },
    )
    .v()
}

#[test]
fn errors_name_the_token_and_its_characters() {
    let (m, s, e) = err("x + y");
    assert!(
        m.contains("unknown name `y`") && m.contains("params are k"),
        "{m}"
    );
    assert_eq!((s, e), (4, 5));
    let (m, s, e) = err("x + 1.0");
    assert!(m.contains("vec3 + f32"), "{m}");
    assert_eq!((s, e), (0, 7));
    let (m, s, e) = err("cross(x)");
    assert!(m.contains("takes 2 arguments, got 1"), "{m}");
    assert_eq!((s, e), (0, 8));
    let (m, s, _) = err("(x * (k + 1.0)");
    assert!(m.contains("unclosed `(`"), "{m}");
    assert_eq!(s, 0);
    let (m, _, _) = err("   ");
    assert!(m.contains("empty"), "{m}");
    let (m, s, e) = err("length(x)");
    assert!(
        m.contains("is a f32, but an acceleration must be a vec3"),
        "{m}"
    );
    assert_eq!((s, e), (0, 9));
    let (m, s, e) = err("x * frob(1.0)");
    assert!(m.contains("unknown function `frob`"), "{m}");
    assert_eq!((s, e), (4, 8));
    let (m, s, e) = err("x * noise(x.x)");
    assert!(m.contains("argument 1 of `noise` must be a vec3"), "{m}");
    assert_eq!((s, e), (10, 13));
    let (m, s, _) = err("x * rand(k)");
    assert!(m.contains("literal"), "{m}");
    assert_eq!(s, 9);
    let (m, _, _) = err("x * 1e30");
    assert!(m.contains("beyond"), "{m}");
    let (m, s, e) = err("x.w * x");
    assert!(m.contains("unknown component `.w`"), "{m}");
    assert_eq!((s, e), (2, 3));
    let (m, _, _) = err("select(x, v, 1.0)");
    assert!(m.contains("must be a bool"), "{m}");
    let (m, _, _) = err("x * (t < 1.0)");
    assert!(m.contains("got a bool"), "{m}");
}

#[test]
fn guards_give_documented_finite_values() {
    let z = DVec3::ZERO;
    let one = DVec3::ONE;
    // Division by zero is 0; sqrt of a negative is 0; log reads max(x, 1e-30).
    assert_eq!(at("x / 0.0", one, z), z);
    assert_eq!(at("x / v.x", one, z), z);
    assert_eq!(at("vec3(sqrt(-4.0), sqrt(v.x - 1.0), 0.0)", z, z), z);
    let l = at("vec3(log(v.x), 0.0, 0.0)", z, z).x;
    assert!((l - (1e-30f64).ln()).abs() < 1e-12, "{l}");
    // pow of a non-positive base is 0; exp and products stay within the bound.
    assert_eq!(at("vec3(pow(v.x - 2.0, 3.0), 0.0, 0.0)", z, z).x, 0.0);
    assert!((at("vec3(pow(v.x + 2.0, 3.0), 0.0, 0.0)", z, z).x - 8.0).abs() < 1e-9);
    let e = at("vec3(exp(v.x + 1000.0), 0.0, 0.0)", z, z).x;
    assert!((e / super::VALUE_BOUND - 1.0).abs() < 1e-12, "{e}");
    let big = DVec3::splat(1e18);
    assert_eq!(at("x * x * x", big, z), big);
    assert_eq!(at("-x * x", big, z), -big);
    // normalize of zero is zero; atan2(0, 0) is 0.
    assert_eq!(at("normalize(v)", z, z), z);
    assert_eq!(at("vec3(atan2(v.x, v.y), 0.0, 0.0)", z, z).x, 0.0);
    // smoothstep with equal edges is 0, not 0/0.
    assert_eq!(
        at("vec3(smoothstep(1.0, 1.0, v.x + 2.0), 0.0, 0.0)", z, z).x,
        0.0
    );
}

#[test]
fn operations_mean_what_they_say() {
    let x = DVec3::new(1.0, 2.0, 3.0);
    let v = DVec3::new(-1.0, 0.5, 4.0);
    assert_eq!(at("cross(x, v)", x, v), x.cross(v));
    assert_eq!(at("x * dot(x, v)", x, v), x * x.dot(v));
    assert_eq!(
        at("min(x, v) + max(x, 2.0)", x, v),
        x.min(v) + x.max(DVec3::splat(2.0))
    );
    assert_eq!(
        at("clamp(v, 0.0, 1.0)", x, v),
        v.clamp(DVec3::ZERO, DVec3::ONE)
    );
    assert_eq!(at("mix(x, v, 0.25)", x, v), x + (v - x) * 0.25);
    assert_eq!(at("step(2.0, x)", x, v), DVec3::new(0.0, 1.0, 1.0));
    assert_eq!(
        at("select(x, v, x.y > 1.5) - select(x, v, x.y < 1.5)", x, v),
        v - x
    );
    assert_eq!(at("vec3(v.z, -v.y, k)", x, v), DVec3::new(4.0, -0.5, 0.5));
    assert_eq!(at("x * dt", x, v), x * 0.01);
    assert_eq!(at("fract(v) + floor(v)", x, v), v);
}

#[test]
fn constants_fold_and_zero_terms_vanish() {
    let g = c("vec3(0.0, -9.81 * 2.0, 0.0) * 1.0 + x * 0.0").unwrap();
    assert_eq!(g.node, Node::Vector(DVec3::new(0.0, -19.62, 0.0)));
    let zero = c("x * (k - 0.5)").unwrap();
    assert!(super::fold::is_zero(&zero));
    let picked = c("select(x, v, k > 0.25)").unwrap();
    assert_eq!(picked.node, Node::Var(super::Var::V));
    let kept = c("-(-x) / 1.0").unwrap();
    assert_eq!(kept.node, Node::Var(super::Var::X));
}

#[test]
fn random_numbers_come_from_the_particle_hash() {
    let e = c("vec3(rand(0), rand(1), rand(0))").unwrap();
    let draw = |id| {
        eval(
            &e,
            &Inputs {
                id,
                seed_mix: 7,
                ..Inputs::default()
            },
        )
    };
    let Value::V(a) = draw(3) else { panic!() };
    assert_eq!(a.x, a.z);
    assert_ne!(a.x, a.y);
    assert!((0.0..1.0).contains(&a.x));
    assert_eq!(draw(3), draw(3));
    assert_ne!(draw(3), draw(4));
}

#[test]
fn hsv_gives_the_hues_and_greys_and_folds_when_constant() {
    let near = |a: DVec3, b: DVec3| (a - b).length() < 1e-6;
    let rgb = |text: &str| at(text, DVec3::ZERO, DVec3::ZERO);
    assert!(near(rgb("hsv(0.0, 1.0, 1.0)"), DVec3::X));
    assert!(near(rgb("hsv(1.0 / 3.0, 1.0, 1.0)"), DVec3::Y));
    assert!(near(rgb("hsv(2.0 / 3.0, 1.0, 0.5)"), DVec3::Z * 0.5));
    assert!(near(rgb("hsv(0.25, 0.0, 0.7)"), DVec3::splat(0.7)));
    // Constant arguments fold the whole helper to a colour.
    assert!(matches!(
        c("hsv(0.0, 1.0, 2.0)").unwrap().node,
        Node::Vector(_)
    ));
    // A mistake in an argument is located in the argument; a vec3 where a number goes, at it.
    let (m, s, e) = err("hsv(x, 1.0, 1.0)");
    assert!(m.contains("argument 1 of `hsv`"), "{m}");
    assert_eq!((s, e), (4, 5));
    let (m, s, _) = err("hsv(0.5, 1.0, nope)");
    assert!(m.contains("unknown name `nope`"), "{m}");
    assert_eq!(s, 14);
}

#[test]
fn draws_take_a_literal_stream_that_leaves_room_for_theirs() {
    let (m, s, e) = err("rand_ball(254) * 1.0");
    assert!(
        m.contains("rand_ball(k) reads rand(k) to rand(k + 2)") && m.contains("0 to 253"),
        "{m}"
    );
    assert_eq!((s, e), (10, 13));
    assert!(c("rand_sphere(254)").is_ok());
    // The expansion reads the particle's own numbers: the same at every evaluation.
    assert!(c("rand_disc(3)").unwrap().draws_random());
}
