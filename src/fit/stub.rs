//! TEMPORARY: the dataset types until src/dataset.rs lands.
#![allow(dead_code)]
use std::path::PathBuf;
#[derive(Clone, Debug)]
pub struct FabricDataset {
    pub name: String,
    pub path: PathBuf,
    pub areal_density: Option<f64>,
    pub thickness: f64,
    pub tensile: Vec<TensileTest>,
    pub bend: Vec<BendTest>,
}
#[derive(Clone, Debug)]
pub struct TensileTest {
    pub angle_deg: f64,
    pub width: f64,
    pub gauge_length: f64,
    pub curve: PathBuf,
    pub elongation: Vec<f64>,
    pub force: Vec<f64>,
}
#[derive(Clone, Debug)]
pub struct BendTest {
    pub angle_deg: f64,
    pub width: f64,
    pub overhang: f64,
    pub drape_angle_deg: f64,
}
impl FabricDataset {
    pub fn tests_at(&self, angle_deg: f64) -> Vec<&TensileTest> {
        self.tensile
            .iter()
            .filter(|t| (t.angle_deg - angle_deg).abs() < 1e-9)
            .collect()
    }
}
