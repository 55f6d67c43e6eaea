//! The plugin's tests, each in a headless Bevy app on lavapipe (Mesa's CPU Vulkan driver),
//! one app at a time (`common::serial`). One test binary, not one a file: each binary links all
//! of Bevy (160 MB without debug info), so one a file would cost minutes of linking and
//! gigabytes of disk.

mod common;

mod assets;
mod batches;
mod bounds;
mod click;
mod compute;
mod diagnostics;
mod layers;
mod lights;
mod meshes;
mod plugin;
mod reports;
mod ribbons;
mod thinning;
mod two_d;
mod variants;
mod when_visible;
