//! The subcommands of the `ridgeline` binary: `fly` (the main job) flies a
//! camera path over a terrain, `accuracy` measures the error it draws against
//! full resolution, `import` builds a node pyramid cache, `info` describes
//! one. Helpers shared by the subcommands live here.

use std::path::Path;

use anyhow::Result;
use glam::UVec2;
use ridgeline::display::DisplayConfig;
use ridgeline::earth::GridPlacement;
use ridgeline::flight::FlightPath;
use ridgeline::lod::budget::{BudgetConfig, BudgetTarget};

pub mod accuracy;
pub mod fly;
pub mod fly_args;
pub mod frames;
pub mod heap;
pub mod import;
pub mod info;
pub mod live;
mod progress;
pub mod terrain;

use terrain::{Flight, Terrain};

/// Writes `text` to standard output. A reader that has gone away (a closed
/// pipe, as in `ridgeline info ... | head`) is not an error.
pub fn print(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(error) if error.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        other => Ok(other?),
    }
}

/// What `fly` and `accuracy` both take: the terrain, the camera path and
/// how the view is drawn.
#[derive(clap::Args)]
pub struct ViewArgs {
    /// Terrain: a cache name under cache/, a path to a pyramid, or
    /// `procedural` (the earth-size procedural source, 38.4 m posts); the
    /// built-in SRTM tile when omitted.
    #[arg(long)]
    pub dataset: Option<String>,
    /// Camera path CSV: t,x,y,alt,heading,pitch,roll (or lat,lon for x,y);
    /// the built-in flight (`--flight`) when omitted.
    #[arg(long, conflicts_with = "flight")]
    pub path: Option<std::path::PathBuf>,
    /// Built-in flight: `approach` (descending over the best data),
    /// `cruise` (level at 10 km, out to the horizon), `edges` (16 views at
    /// 300 m above the ground along, across and past each of the data's
    /// four edges) or `outline` (16 views along the data's no-data outline
    /// inside the grid); with `accuracy`, `--views 16` lands on each.
    #[arg(long, value_enum, default_value_t = Flight::Approach)]
    pub flight: Flight,
    /// Image or window size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: UVec2,
    /// Screen-space error bound in pixels.
    #[arg(long, default_value_t = 1.0)]
    pub tau: f64,
    /// Horizontal field of view in degrees.
    #[arg(long, default_value_t = 60.0)]
    pub fov: f64,
    /// Draw each level's posts as a regular grid instead of the node
    /// meshes (Ulrich's chunks: each tile's mesh extracted from its node's
    /// error map at the error its ring allows), which draw many times
    /// fewer triangles for the same bound.
    #[arg(long)]
    pub regular_grid: bool,
    /// Triangles a frame to hold by raising tau above --tau (never below);
    /// every frame records the tau it achieved.
    #[arg(long, conflicts_with = "frame_ms")]
    pub triangle_budget: Option<u64>,
    /// Milliseconds a frame to aim at, through the same controller as
    /// --triangle-budget.
    #[arg(long, allow_hyphen_values = true)]
    pub frame_ms: Option<f64>,
    /// The camera's largest speed, metres a second, that split tests'
    /// valid life assumes (faster frames re-test every tile); the path's
    /// fastest leg when omitted.
    #[arg(long, allow_hyphen_values = true)]
    pub max_speed: Option<f64>,
    /// Draw in the planar chart (equirectangular at the grid's centre
    /// latitude, or a projected grid's own plane, lowered by d^2 / 2R), as
    /// before issue 26's phase B, instead of on the WGS 84 ellipsoid: a
    /// fallback, and the "before" of a comparison. Grids of an unknown
    /// projection, and local grids, are drawn in the chart either way.
    #[arg(long)]
    pub chart: bool,
}

impl ViewArgs {
    /// Refuses a tau or field of view no view can be drawn with.
    fn check(&self) -> Result<()> {
        if !(self.tau.is_finite() && self.tau > 0.0) {
            anyhow::bail!("--tau {} must be a number of pixels above 0", self.tau);
        }
        if !(self.fov.is_finite() && self.fov > 0.0 && self.fov < 179.0) {
            anyhow::bail!("--fov {} must be between 0 and 179 degrees", self.fov);
        }
        if self.triangle_budget == Some(0) {
            anyhow::bail!("--triangle-budget 0: a frame needs at least 1 triangle");
        }
        if let Some(ms) = self.frame_ms.filter(|m| !(m.is_finite() && *m > 0.0)) {
            anyhow::bail!("--frame-ms {ms} must be a number of milliseconds above 0");
        }
        if let Some(speed) = self.max_speed.filter(|v| !(v.is_finite() && *v > 0.0)) {
            anyhow::bail!("--max-speed {speed} must be a number of metres a second above 0");
        }
        Ok(())
    }

    /// Opens the terrain (see [`terrain`]).
    /// The frame budget the options ask for, if any.
    fn budget(&self) -> Option<BudgetConfig> {
        let target = match (self.triangle_budget, self.frame_ms) {
            (Some(n), _) => BudgetTarget::Triangles(n),
            (None, Some(ms)) => BudgetTarget::FrameMs(ms),
            (None, None) => return None,
        };
        Some(BudgetConfig::new(target))
    }

    /// Draws on the ellipsoid unless `--chart`: the placement of `terrain`'s grid.
    fn configure_earth(&self, config: &mut DisplayConfig, terrain: &Terrain) {
        let layout = terrain.source.layout();
        let placement = GridPlacement::new(&terrain.georef(), layout.posts, layout.spacing_m);
        config.scene.earth = (!self.chart).then_some(placement);
    }

    /// Applies tau, the field of view, the budget and the valid life's
    /// declared travel (`--max-speed`, else `path`'s fastest leg, on the
    /// earth when the display draws there, times
    /// `frame_interval_s`) to `config`.
    fn configure(&self, config: &mut DisplayConfig, path: &FlightPath, frame_interval_s: f64) {
        let speed =
            self.max_speed.unwrap_or_else(|| path.max_speed_over(config.scene.earth.as_ref()));
        self.configure_at(config, speed, frame_interval_s);
    }

    /// [`ViewArgs::configure`] for a camera moving at most `speed` m/s.
    fn configure_at(&self, config: &mut DisplayConfig, speed: f64, frame_interval_s: f64) {
        config.scene.lod.tau_px = self.tau;
        config.fov_x_deg = self.fov;
        config.budget = self.budget();
        config.scene.lod.max_travel_m = Some((speed * frame_interval_s * 1.001).max(1e-3));
    }

    /// Opens the terrain: the pyramid, the source the display pages nodes
    /// from (with their adaptive meshes unless `--regular-grid`), and the
    /// per-level errors its rings are computed from.
    fn open_terrain(&self, progress: &dyn ridgeline::pyramid::Progress) -> Result<Terrain> {
        Terrain::open(self, progress)
    }
}

/// Writes `bytes` beside `path` and renames them into place, so a reader
/// never sees half a file.
fn write_beside(path: &Path, bytes: &[u8]) -> Result<()> {
    use anyhow::Context as _;
    let mut partial = path.as_os_str().to_owned();
    partial.push(".tmp");
    let partial = std::path::PathBuf::from(partial);
    std::fs::write(&partial, bytes)
        .with_context(|| format!("{}: cannot write", partial.display()))?;
    std::fs::rename(&partial, path)
        .with_context(|| format!("{}: cannot rename into place", path.display()))
}

/// Writes `image` as a PNG at `path`, beside and renamed.
fn save_png(image: &image::RgbaImage, path: &Path) -> Result<()> {
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png)?;
    write_beside(path, &bytes)
}

/// Parses `--size WIDTHxHEIGHT`.
fn parse_size(text: &str) -> Result<UVec2, String> {
    let (w, h) =
        text.split_once(['x', 'X']).ok_or_else(|| format!("size `{text}` is not WIDTHxHEIGHT"))?;
    let parse = |s: &str| {
        s.trim().parse::<u32>().map_err(|_| format!("size `{text}`: `{s}` is not a whole number"))
    };
    let size = UVec2::new(parse(w)?, parse(h)?);
    if size.x == 0 || size.y == 0 || size.x > 16384 || size.y > 16384 {
        return Err(format!("size `{text}` must be between 1x1 and 16384x16384"));
    }
    Ok(size)
}
