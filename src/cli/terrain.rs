//! The terrain and camera path of a `fly` or `accuracy` run: a pyramid (the
//! built-in terrain, a cache name or a path) or `--dataset procedural`, the
//! earth-size procedural source; `--path FILE.csv` or a built-in flight
//! (`--flight approach|cruise`).

use std::path::Path;
use std::sync::Arc;

use anyhow::{bail, Result};
use ridgeline::flight::{
    builtin_approach_over, builtin_cruise, builtin_edges, builtin_outline, default_flight,
    FlightPath,
};
use ridgeline::geo::GeoRef;
use ridgeline::meshes::{MeshOptions, MeshedSource};
use ridgeline::node::NodeSource;
use ridgeline::procedural::{EarthParams, ProceduralEarth};
use ridgeline::pyramid::{Progress, Pyramid};
use ridgeline::scene::TerrainSummary;

use super::ViewArgs;

/// The `--dataset` name of the earth-size procedural source.
pub const PROCEDURAL: &str = "procedural";

/// A built-in flight, flown when no `--path` is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Flight {
    /// The descending approach over the best data.
    Approach,
    /// Level at 10 km, looking out to the horizon.
    Cruise,
    /// Sixteen views at 300 m above the ground along, across and past each
    /// of the best data's four edges (`flight::edges`).
    Edges,
    /// Sixteen views at 300 m above the ground along the data's no-data
    /// outline inside the grid, in turn inside and past it.
    Outline,
}

/// Where a terrain's heights come from.
pub enum Ground {
    /// A node pyramid on disk.
    Pyramid(Arc<Pyramid>),
    /// The earth-size procedural source.
    Procedural(Arc<ProceduralEarth>),
}

/// An opened terrain: its heights, the source the display pages nodes
/// from, the per-level errors its rings are computed from, its name.
pub struct Terrain {
    pub ground: Ground,
    pub source: Arc<dyn NodeSource>,
    pub summary: TerrainSummary,
    pub name: String,
}

impl Terrain {
    /// Opens what `view` names (see the module doc).
    pub fn open(view: &ViewArgs, progress: &dyn Progress) -> Result<Terrain> {
        if view.dataset.as_deref() == Some(PROCEDURAL) {
            return open_procedural();
        }
        let cache = Path::new("cache");
        let pyramid = Arc::new(ridgeline::dataset::open(view.dataset.as_deref(), cache, progress)?);
        let mut summary = TerrainSummary::from_pyramid(pyramid.info());
        let name = pyramid.path().display().to_string();
        let source: Arc<dyn NodeSource> = if view.regular_grid {
            pyramid.clone()
        } else {
            let options = MeshOptions::default();
            let meshed = MeshedSource::open_or_build(Arc::clone(&pyramid), options, progress)?;
            summary = TerrainSummary::of_maps(pyramid.info(), meshed.info());
            Arc::new(meshed)
        };
        Ok(Terrain { ground: Ground::Pyramid(pyramid), source, summary, name })
    }

    /// The georeference of the terrain's posts (the procedural earth has
    /// none: a local grid).
    pub fn georef(&self) -> GeoRef {
        match &self.ground {
            Ground::Pyramid(pyramid) => pyramid.info().georef,
            Ground::Procedural(earth) => GeoRef::local(earth.layout().spacing_m),
        }
    }

    /// The full-resolution height at a local point, metres (`None` outside the data).
    pub fn exact_height(&self, x: f64, y: f64) -> Option<f32> {
        match &self.ground {
            Ground::Pyramid(pyramid) => pyramid.exact_height(x, y),
            Ground::Procedural(earth) => earth.exact_height(x, y).ok(),
        }
    }

    /// The camera path: `path`'s CSV, else the built-in `flight` over the
    /// best data (the middle of the procedural earth).
    pub fn flight_path(&self, path: Option<&Path>, flight: Flight) -> Result<FlightPath> {
        let height = |x: f64, y: f64| self.exact_height(x, y);
        match (&self.ground, path) {
            (Ground::Pyramid(pyramid), Some(file)) => {
                let layout = *pyramid.layout();
                let path = FlightPath::read(file, &pyramid.info().georef, layout.posts)?;
                if let Some(note) = path.longitude_note() {
                    eprintln!("{}: {note}", file.display());
                }
                Ok(path)
            }
            (Ground::Procedural(_), Some(_)) => {
                bail!("--path over --dataset procedural: it has no georeference; use --flight")
            }
            (Ground::Pyramid(pyramid), None) => {
                let (origin, extent) = pyramid.finest_area_m();
                Ok(match flight {
                    Flight::Approach => default_flight(pyramid),
                    Flight::Cruise => builtin_cruise(origin, extent, &height),
                    Flight::Edges => builtin_edges(origin, extent, &height),
                    Flight::Outline => {
                        builtin_outline(origin, extent, &height).ok_or_else(|| {
                            anyhow::anyhow!(
                                "--flight outline: {} has no no-data outline inside its grid",
                                self.name
                            )
                        })?
                    }
                })
            }
            (Ground::Procedural(earth), None) => {
                let (origin, extent) = earth.flight_area_m();
                Ok(match flight {
                    Flight::Approach => {
                        builtin_approach_over(origin, extent, &|x, y| height(x, y).unwrap_or(0.0))
                    }
                    Flight::Cruise => builtin_cruise(origin, extent, &height),
                    Flight::Edges | Flight::Outline => {
                        bail!("--flight edges and outline: the procedural earth has no edge")
                    }
                })
            }
        }
    }
}

/// The procedural earth of [`EarthParams::display_earth`], drawn as regular grids.
fn open_procedural() -> Result<Terrain> {
    let earth = Arc::new(ProceduralEarth::new(EarthParams::display_earth())?);
    let summary = TerrainSummary::from_procedural(&earth);
    let source: Arc<dyn NodeSource> = earth.clone();
    let name = PROCEDURAL.to_string();
    Ok(Terrain { ground: Ground::Procedural(earth), source, summary, name })
}
