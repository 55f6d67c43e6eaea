//! Semantic checks of a parsed effect: every value that would make the IR meaningless
//! (non-finite numbers, zero directions, empty lists, inverted ranges, ...) is an error here,
//! named by its path, so lowering and code generation never see bad input.

use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::features::forces::force_path;
use crate::features::looks;
use crate::stages::schema::{EffectSpec, KillVolume, Orient};

/// The most emitters an effect may have: each takes 16 bytes of the per-step uniform, and
/// 16 + 16 x 1023 bytes is the 16 KiB every WebGPU adapter must allow in a uniform binding.
pub const MAX_EMITTERS: usize = 1023;
/// The most forces (before folding): each can add a block to the fused update kernel, and the
/// largest kernels tested run on llvmpipe (400 terms, tests/extremes.rs). Past this, shader
/// compilers slow down sharply and drivers may refuse the kernel.
pub const MAX_FORCES: usize = 512;
/// The most colliders, and separately the most kill volumes (same reason as forces).
pub(crate) const MAX_VOLUMES: usize = 256;

/// Checks the whole effect; returns the checker holding every error found.
pub(crate) fn check_effect(effect: &EffectSpec) -> Checker {
    let mut c = Checker::default();
    let root = ValuePath::root();
    for (field, len, max, why) in [
        (
            "emitters",
            effect.emitters.len(),
            MAX_EMITTERS,
            "each takes 16 bytes of the 16 KiB per-step uniform every adapter allows",
        ),
        (
            "forces",
            effect.forces.len(),
            MAX_FORCES,
            "larger fused kernels are untested and may be refused by drivers",
        ),
        (
            "collide",
            effect.collide.len(),
            MAX_VOLUMES,
            "larger fused kernels are untested and may be refused by drivers",
        ),
        (
            "kill",
            effect.kill.len(),
            MAX_VOLUMES,
            "larger fused kernels are untested and may be refused by drivers",
        ),
    ] {
        if len > max {
            c.error(
                &root.field(field),
                format!("has {len} entries, more than the {max} one kernel can hold ({why})"),
            );
        }
    }
    if effect.capacity == 0 {
        c.error(&root.field("capacity"), "must be >= 1, got 0");
    }
    c.positive(&root.field("dt"), effect.dt);
    if let Some(budget) = &effect.accuracy {
        crate::features::accuracy::check(&mut c, &root.field("accuracy"), budget, effect.dt);
    }
    if effect.substeps == 0 {
        c.error(&root.field("substeps"), "must be >= 1, got 0");
    }
    let (defines, define_errors) = crate::expr::define::parse_all(&effect.define);
    let names = crate::stages::lower::names;
    let attrs =
        crate::features::attributes::names(&effect.attributes, names(effect, &defines, &[]));
    let scope = names(effect, &defines, &attrs);
    check_defines(&mut c, &root.field("define"), effect, define_errors, scope);
    crate::features::attributes::check(
        &mut c,
        &root.field("attributes"),
        &effect.attributes,
        scope,
    );
    for (i, e) in effect.emitters.iter().enumerate() {
        e.check(&mut c, &root.field("emitters").index(i), scope);
    }
    let changing = effect.forces.iter().position(|f| f.changes_when_baked());
    effect.field.check(&root.field("field"), &mut c, changing);
    check_params(&mut c, &root.field("params"), effect);
    for (i, f) in effect.forces.iter().enumerate() {
        f.check(&force_path(i, f), &mut c, scope);
        // A force an effect has at most one of, and what to do instead of a second.
        if let Some(instead) = f.at_most_one() {
            if effect.forces[..i].iter().any(|e| e.name() == f.name()) {
                c.error(
                    &force_path(i, f),
                    format!("a second {}: {instead}", f.name()),
                );
            }
        }
    }
    if let Some(s) = effect.max_speed {
        c.positive(&root.field("max_speed"), s);
    }
    crate::features::scene::check(&effect.scene, &mut c);
    crate::features::lights::check(&effect.lights, &mut c);
    for (i, collider) in effect.collide.iter().enumerate() {
        let path = crate::features::colliders::collider_path(i, collider);
        collider.check(&path, &mut c);
        // A collider an effect has at most one of: why, and what to do instead.
        if let Some(once) = collider.at_most_one() {
            if effect.collide[..i]
                .iter()
                .any(|e| e.name() == collider.name())
            {
                c.error(&path, once);
            }
        }
    }
    for (i, k) in effect.kill.iter().enumerate() {
        let p = root.field("kill").index(i);
        match k {
            KillVolume::InsideBox { min, max } => {
                c.box_corners(&p.variant("InsideBox"), *min, *max)
            }
            KillVolume::OutsideBox { min, max } => {
                c.box_corners(&p.variant("OutsideBox"), *min, *max)
            }
            KillVolume::InsideSphere { center, radius } => {
                let p = p.variant("InsideSphere");
                c.vec3(&p.field("center"), *center);
                c.positive(&p.field("radius"), *radius);
            }
            KillVolume::OutsideSphere { center, radius } => {
                let p = p.variant("OutsideSphere");
                c.vec3(&p.field("center"), *center);
                c.positive(&p.field("radius"), *radius);
            }
        }
    }
    check_render(&mut c, &root.field("render"), &effect.render);
    if let Some(ribbon) = &effect.render.ribbon {
        let r = &effect.render;
        let set = |field: &str| match field {
            "trail" => r.trail.is_some(),
            "texture" => r.texture.is_some(),
            "lit" => r.lit.is_some(),
            "size_y" => r.size_y.is_some(),
            "rotation" => r.rotation.is_some(),
            "orient" => !matches!(r.orient, Orient::Camera),
            _ => false,
        };
        ribbon.check(&root, &set, effect.sort, &mut c);
    }
    if let Some(mesh) = &effect.render.mesh {
        let r = &effect.render;
        let set = |field: &str| match field {
            "trail" => r.trail.is_some(),
            "texture" => r.texture.is_some(),
            "ribbon" => r.ribbon.is_some(),
            "soft" => r.soft.is_some(),
            _ => false,
        };
        mesh.check(&root.field("render"), &set, &mut c);
    }
    crate::features::looks::by_expression::LookBy::check(
        &mut c,
        &root.field("render"),
        effect.render.written_by(),
        scope,
    );
    if let Some(bounds) = &effect.bounds {
        c.box_corners(&root.field("bounds"), bounds.min, bounds.max);
    }
    let cam = root.field("camera");
    let eye_ok = c.vec3(&cam.field("eye"), effect.camera.eye);
    let target_ok = c.vec3(&cam.field("target"), effect.camera.target);
    if eye_ok
        && target_ok
        && (effect.camera.eye.d() - effect.camera.target.d()).length_squared() <= 1e-20
    {
        c.error(&cam.field("target"), "must differ from camera.eye");
    }
    if c.finite(&cam.field("fov_y"), effect.camera.fov_y)
        && !(effect.camera.fov_y > 0.0 && effect.camera.fov_y < 180.0)
    {
        c.error(
            &cam.field("fov_y"),
            format!("must be in (0, 180) degrees, got {}", effect.camera.fov_y),
        );
    }
    c
}

/// Named expressions: names that hide no other name, text that parses, refers to no circle,
/// and type-checks where every variable and attribute is known (a place that knows fewer
/// reports a name it cannot read where it reads the definition).
fn check_defines(
    c: &mut Checker,
    path: &ValuePath,
    effect: &EffectSpec,
    errors: Vec<crate::expr::define::DefineError>,
    names: crate::expr::Names,
) {
    use crate::expr::typed::{EVERY_VARIABLE, FUNCTIONS};
    for (name, e) in errors {
        c.error_in_string(&path.field(&name), e.start, e.end, e.message);
    }
    for name in effect.define.keys() {
        let mut chars = name.chars();
        let identifier = chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
            && chars.all(|c| c.is_alphanumeric() || c == '_');
        if !identifier {
            c.error(
                &path.field(name),
                format!("`{name}` is not a name an expression can use: start with a letter, then letters, digits or _"),
            );
        } else if name == "dt"
            || EVERY_VARIABLE.iter().any(|v| v.name() == name)
            || FUNCTIONS.iter().any(|(f, _)| f == name)
            || effect.params.contains_key(name)
            || effect.attributes.contains_key(name)
        {
            c.error(
                &path.field(name),
                format!("`{name}` is already a variable, function, param or attribute in expressions: pick another name"),
            );
        }
    }
    for d in names.defines {
        let crate::expr::define::Body::Parsed(ast) = &d.body else {
            continue;
        };
        let scope = names.scope_with_attrs(EVERY_VARIABLE, "a named expression");
        if let Err(e) = crate::expr::typed::check(ast, &scope) {
            c.error_in_string(&path.field(&d.name), e.start, e.end, e.message);
        }
    }
}

/// Params: names that expressions can use (identifiers that hide no variable or function),
/// values within the range expressions compute in.
fn check_params(c: &mut Checker, path: &ValuePath, effect: &EffectSpec) {
    use crate::expr::typed::{EVERY_VARIABLE, FUNCTIONS};
    for (component, &value) in &effect.params {
        // A vector's components (`wind.x`) are checked by its name.
        let name = ["x", "y", "z"]
            .iter()
            .find_map(|c| component.strip_suffix(&format!(".{c}")))
            .unwrap_or(component);
        let p = path.field(name);
        let mut chars = name.chars();
        let identifier = chars.next().is_some_and(|c| c.is_alphabetic() || c == '_')
            && chars.all(|c| c.is_alphanumeric() || c == '_');
        // A vector's name is checked once, with its first component.
        let named_here = component == name || component.ends_with(".x");
        if named_here && !identifier {
            c.error(
                &p,
                format!("`{name}` is not a name an expression can use: start with a letter, then letters, digits or _"),
            );
        } else if named_here
            && (name == "dt"
                || EVERY_VARIABLE.iter().any(|v| v.name() == name)
                || FUNCTIONS.iter().any(|(f, _)| *f == name))
        {
            c.error(
                &p,
                format!(
                    "`{name}` is already a variable or function in expressions: pick another name"
                ),
            );
        }
        // A vector's component is named and located as the tuple's element.
        let p = match ["x", "y", "z"]
            .iter()
            .position(|c| component.len() > name.len() && component.ends_with(c))
        {
            Some(k) => p.component(k, ["x", "y", "z"][k]),
            None => p,
        };
        if c.finite(&p, value) && value.abs() > crate::expr::VALUE_BOUND {
            c.error(
                &p,
                format!(
                    "must be within ±{:e} (the range expressions compute in), got {value:e}",
                    crate::expr::VALUE_BOUND
                ),
            );
        }
    }
}

fn check_render(c: &mut Checker, path: &ValuePath, r: &crate::stages::schema::Render) {
    let flipbook = r
        .texture
        .as_ref()
        .is_some_and(|t| u64::from(t.frames.0) * u64::from(t.frames.1) > 1);
    if r.frame_by.is_some() && !flipbook {
        c.error(
            &path.field("frame_by"),
            "picks a flipbook frame, but there is no flipbook: give render.texture with frames: (columns, rows) of more than one",
        );
    }
    r.blend.check(&path.field("blend"), c);
    looks::check_colors(c, &path.field("color"), &r.color);
    looks::check_sizes(c, &path.field("size"), &r.size, "size");
    if let Some(heights) = &r.size_y {
        looks::check_sizes(c, &path.field("size_y"), heights, "size");
    }
    if let Some(alpha) = &r.alpha {
        looks::check_alphas(c, &path.field("alpha"), alpha);
    }
    if let Some(t) = &r.trail {
        t.check(c, &path.field("trail"));
    }
    if let Some(light) = &r.light {
        light.check(&path.field("light"), c);
    }
    if let Some(lit) = &r.lit {
        lit.check(&path.field("lit"), r.texture.is_some(), c);
    }
    if let Some(palette) = &r.palette {
        crate::features::looks::tint::check_palette(c, &path.field("palette"), palette);
    }
    let bg = path.field("background");
    for (j, (name, x)) in [
        ("r", r.background.0),
        ("g", r.background.1),
        ("b", r.background.2),
    ]
    .into_iter()
    .enumerate()
    {
        c.within(&bg.component(j, name), x, 0.0, 1.0);
    }
    r.orient.check(&path.field("orient"), c);
    if let Some(t) = &r.texture {
        t.check(&path.field("texture"), c);
    }
    if let Some(d) = r.soft {
        c.positive(&path.field("soft"), d);
    }
    if let Some(g) = &r.glow {
        g.check(&path.field("glow"), c);
    }
    if let Some(rotation) = &r.rotation {
        rotation.check(&path.field("rotation"), r.orient, c);
    }
}
