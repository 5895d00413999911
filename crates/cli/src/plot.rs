//! Temporary stand-in for the SVG plot module (being written).
#![allow(missing_docs, dead_code)]
pub struct Series {
    pub name: String,
    pub values: Vec<f64>,
}
pub struct PlotData {
    pub title: String,
    pub subtitle: String,
    pub time: Vec<f64>,
    pub coordinates: Vec<Series>,
    pub velocities: Vec<Series>,
    pub invariants: Vec<Series>,
}
pub fn write_svg(_path: &std::path::Path, _data: &PlotData) -> Result<(), String> {
    Ok(())
}
