//! The `Collider` enum as effect files write it: each variant's schema, checks and lowering
//! live in the variant's own module ([`plane`], [`sphere`], [`aabb`], [`height_field`],
//! [`mesh`], [`scene_depth`]); this enum reads `Name(field: value, ...)` into them and hands
//! each call on.

use serde::de::{self, Deserialize, Deserializer, EnumAccess};

use super::{aabb, height_field, mesh, plane, scene_depth, sphere, ColliderIr};
use crate::base::check::Checker;
use crate::base::path::ValuePath;
use crate::base::values::struct_variant;

/// A collider as written in an effect file.
#[derive(Clone, Debug, PartialEq)]
pub enum Collider {
    /// A half-space boundary.
    Plane(plane::Plane),
    /// A ball, solid or a container.
    Sphere(sphere::Sphere),
    /// An axis-aligned box, solid or a container.
    Box(aabb::Aabb),
    /// Terrain: heights on a grid.
    HeightField(height_field::HeightField),
    /// A closed triangle mesh.
    Mesh(mesh::Mesh),
    /// The surfaces the view's depth image shows.
    SceneDepth(scene_depth::SceneDepth),
}

impl Collider {
    /// The variant's name as written in effect files.
    pub fn name(&self) -> &'static str {
        match self {
            Collider::Plane(_) => "Plane",
            Collider::Sphere(_) => "Sphere",
            Collider::Box(_) => "Box",
            Collider::HeightField(_) => "HeightField",
            Collider::Mesh(_) => "Mesh",
            Collider::SceneDepth(_) => "SceneDepth",
        }
    }

    /// For a collider an effect may have only one of: why, and what to do instead of a second.
    pub(crate) fn at_most_one(&self) -> Option<&'static str> {
        match self {
            Collider::SceneDepth(_) => Some("an effect collides with the scene's depth once: one SceneDepth collider (give it the thickness it needs)"),
            _ => None,
        }
    }

    /// Checks the collider's parameters; `path` names the variant.
    pub(crate) fn check(&self, path: &ValuePath, c: &mut Checker) {
        match self {
            Collider::Plane(x) => x.check(path, c),
            Collider::Sphere(x) => x.check(path, c),
            Collider::Box(x) => x.check(path, c),
            Collider::HeightField(x) => x.check(path, c),
            Collider::Mesh(x) => x.check(path, c),
            Collider::SceneDepth(x) => x.check(path, c),
        }
    }

    /// Lowers a checked collider to the IR.
    pub(crate) fn lower(&self) -> ColliderIr {
        match self {
            Collider::Plane(x) => x.lower(),
            Collider::Sphere(x) => x.lower(),
            Collider::Box(x) => x.lower(),
            Collider::HeightField(x) => x.lower(),
            Collider::Mesh(x) => x.lower(),
            Collider::SceneDepth(x) => x.lower(),
        }
    }
}

/// The variant names as files write them.
const VARIANTS: &[&str] = &[
    "Plane",
    "Sphere",
    "Box",
    "HeightField",
    "Mesh",
    "SceneDepth",
];

/// The variant names (serde reports unknown ones with the list of expected names).
#[derive(serde::Deserialize)]
#[serde(variant_identifier)]
enum Kind {
    Plane,
    Sphere,
    Box,
    HeightField,
    Mesh,
    SceneDepth,
}

struct ColliderVisitor;

impl<'de> de::Visitor<'de> for ColliderVisitor {
    type Value = Collider;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a collider: Plane, Sphere, Box, HeightField, Mesh or SceneDepth")
    }
    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Collider, A::Error> {
        let (kind, variant): (Kind, _) = data.variant()?;
        Ok(match kind {
            Kind::Plane => Collider::Plane(struct_variant(variant, plane::FIELDS)?),
            Kind::Sphere => Collider::Sphere(struct_variant(variant, sphere::FIELDS)?),
            Kind::Box => Collider::Box(struct_variant(variant, aabb::FIELDS)?),
            Kind::HeightField => {
                Collider::HeightField(struct_variant(variant, height_field::FIELDS)?)
            }
            Kind::Mesh => Collider::Mesh(struct_variant(variant, mesh::FIELDS)?),
            Kind::SceneDepth => Collider::SceneDepth(struct_variant(variant, scene_depth::FIELDS)?),
        })
    }
}

impl<'de> Deserialize<'de> for Collider {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_enum("Collider", VARIANTS, ColliderVisitor)
    }
}

/// Path of the `i`-th collider, with its variant named.
pub(crate) fn collider_path(i: usize, c: &Collider) -> ValuePath {
    ValuePath::root()
        .field("collide")
        .index(i)
        .variant(c.name())
}
