//! The end-to-end, oracle and command-line tests, in one test binary so that the library and
//! its dependencies link once. Each module is one topic; `common` holds the shared fixtures.
//! (`tests/dump.rs` stays a binary of its own: it sets an environment variable that every
//! solve in its process reads.)

mod basis;
mod batch;
mod benchmarks;
mod bounds;
mod cantilever;
mod cli;
mod common;
mod dataset;
mod degrees;
mod fit;
mod fit_lab;
mod force_curves;
mod hostile;
mod joint;
mod layers;
mod model_cli;
mod off_axis;
mod opensubdiv_oracle;
mod orthotropic;
mod outputs;
mod plausible_data;
mod polish;
mod refinement;
mod render;
mod render_cli;
mod report;
mod scene_cli;
mod scenes;
mod sensitivities;
mod shape_fit;
mod shell;
mod stability_atlas;
mod strategies;
mod tri_fit;
mod tri_models;
mod tri_scenes;
mod tri_strips;
mod zoo;
