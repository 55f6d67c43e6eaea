//! Bevy meshes as mesh particles: `PlumeEffect::with_mesh(handle)` draws every particle of an
//! effect's top group as that mesh (as `render.mesh` draws an OBJ file's), whatever the file's
//! look says. For each pair of effect file and mesh an entity names, the main world compiles
//! the file again with the mesh as its particles' mesh ([`PlumeEffectAsset::with_mesh`], on
//! Bevy's async compute pool) into an asset of its own, which the entity's instance then runs;
//! until it is ready the entity draws nothing. A hot reload of the file, or a change to the
//! mesh, compiles it again.

use bevy::asset::AssetEvent;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task};

use crate::asset::PlumeEffectAsset;
use crate::effect::PlumeEffect;

/// An effect file and the mesh its particles are drawn as.
type Pair = (AssetId<PlumeEffectAsset>, AssetId<Mesh>);

/// A compile of a file with a mesh: the file's version (by address) and the task.
type Compile = (usize, Task<Result<PlumeEffectAsset, String>>);

/// The effect files compiled with a Bevy mesh, by (file, mesh).
#[derive(Resource, Default)]
pub(crate) struct MeshedEffects {
    /// The compiled asset, and the file's version it was compiled from (by address).
    ready: HashMap<Pair, (Handle<PlumeEffectAsset>, usize)>,
    /// Compiles under way.
    compiling: HashMap<Pair, Compile>,
}

impl MeshedEffects {
    /// The asset an entity with `effect` drawn as `mesh` runs, once compiled.
    pub(crate) fn get(
        &self,
        effect: &Handle<PlumeEffectAsset>,
        mesh: &Handle<Mesh>,
    ) -> Option<&Handle<PlumeEffectAsset>> {
        self.ready.get(&(effect.id(), mesh.id())).map(|(h, _)| h)
    }
}

/// A mesh as OBJ text for the compiler: its positions and triangles (a triangle list, indexed
/// or not; Bevy's front faces wind counter-clockwise, as OBJ's do).
pub fn obj_of(mesh: &Mesh) -> Result<Vec<u8>, String> {
    if mesh.primitive_topology() != PrimitiveTopology::TriangleList {
        return Err(format!(
            "a mesh particle needs a triangle list, not {:?}",
            mesh.primitive_topology()
        ));
    }
    let positions = mesh
        .try_attribute(Mesh::ATTRIBUTE_POSITION)
        .ok()
        .and_then(|a| a.as_float3())
        .ok_or("a mesh particle needs the mesh's positions (Float32x3) in the main world")?;
    let corners: Vec<usize> = match mesh.try_indices() {
        Ok(Indices::U16(i)) => i.iter().map(|&i| usize::from(i)).collect(),
        Ok(Indices::U32(i)) => i.iter().map(|&i| i as usize).collect(),
        Err(_) => (0..positions.len()).collect(),
    };
    let mut obj = String::with_capacity(32 * (positions.len() + corners.len() / 3));
    for p in positions {
        obj.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    for t in corners.chunks_exact(3) {
        if t.iter().any(|&i| i >= positions.len()) {
            return Err("the mesh's indices point past its positions".into());
        }
        obj.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    Ok(obj.into_bytes())
}

/// Compiles, for each (file, mesh) an effect entity names, the file with the mesh, off the
/// main thread; puts finished ones in [`MeshedEffects`] and the assets. A file's new version
/// or a mesh's change compiles it again.
pub(crate) fn compile_meshed_effects(
    mut meshed: ResMut<MeshedEffects>,
    effects: Query<&PlumeEffect>,
    mut assets: ResMut<Assets<PlumeEffectAsset>>,
    meshes: Res<Assets<Mesh>>,
    mut mesh_events: MessageReader<AssetEvent<Mesh>>,
) {
    let meshed = &mut *meshed;
    for event in mesh_events.read() {
        if let AssetEvent::Modified { id } = event {
            meshed.ready.retain(|(_, mesh), _| mesh != id);
        }
    }
    // Finished compiles.
    let done: Vec<_> = meshed
        .compiling
        .iter()
        .filter(|(_, (_, task))| task.is_finished())
        .map(|(key, _)| *key)
        .collect();
    for key in done {
        let Some((version, task)) = meshed.compiling.remove(&key) else {
            continue;
        };
        match bevy::tasks::block_on(task) {
            Ok(asset) => {
                let handle = assets.add(asset);
                meshed.ready.insert(key, (handle, version));
            }
            Err(message) => error!("{message}"),
        }
    }
    for effect in &effects {
        let Some(mesh_handle) = &effect.mesh else {
            continue;
        };
        let key = (effect.handle.id(), mesh_handle.id());
        let (Some(file), Some(mesh)) = (assets.get(&effect.handle), meshes.get(mesh_handle)) else {
            continue;
        };
        let version = std::sync::Arc::as_ptr(&file.graph) as usize;
        let current = meshed.ready.get(&key).is_some_and(|(_, v)| *v == version);
        let under_way = meshed
            .compiling
            .get(&key)
            .is_some_and(|(v, _)| *v == version);
        if current || under_way {
            continue;
        }
        let obj = match obj_of(mesh) {
            Ok(obj) => obj,
            Err(why) => {
                warn_once!("{}: {why}", file.path);
                continue;
            }
        };
        let file = file.clone();
        match AsyncComputeTaskPool::try_get() {
            Some(pool) => {
                let task = pool.spawn(async move { file.with_mesh(obj) });
                meshed.compiling.insert(key, (version, task));
            }
            // No pool (an app without Bevy's task pools): compiled here.
            None => match file.with_mesh(obj) {
                Ok(asset) => {
                    let handle = assets.add(asset);
                    meshed.ready.insert(key, (handle, version));
                }
                Err(message) => error!("{message}"),
            },
        }
    }
}
