//! `ridgeline fly`'s options, shared by path runs (`fly`) and live runs
//! (`live`).

use std::path::PathBuf;

use ridgeline::gl::GlBackend;
use ridgeline::input::InputSpec;

#[derive(clap::Args)]
pub struct FlyArgs {
    #[command(flatten)]
    pub view: super::ViewArgs,
    /// Headless: frames at evenly spaced times along the path.
    #[arg(long, default_value_t = 120)]
    pub frames: u32,
    #[arg(long, value_enum, default_value_t = GlBackend::Auto)]
    pub backend: GlBackend,
    /// Ask for an OpenGL ES 2.0 context (the low-end path).
    #[arg(long)]
    pub es2: bool,
    /// Where headless runs write their images and stats.json.
    #[arg(long, default_value = "target/fly")]
    pub out: PathBuf,
    /// Terrain this many metres above the aircraft, or higher, is red
    /// (default -30.48: terrain above or within 100 ft below the aircraft,
    /// Garmin's SVT/TAWS convention).
    #[arg(long, default_value_t = ridgeline::render::palette::DEFAULT_WARNING_ABOVE_M)]
    pub warning_above: f32,
    /// Terrain less than this many metres below the aircraft is amber
    /// (default 304.8 m, 1000 ft: Garmin's yellow band, 100 to 1000 ft below).
    #[arg(long, default_value_t = ridgeline::render::palette::DEFAULT_CAUTION_BELOW_M)]
    pub caution_below: f32,
    /// Draw a flat earth (no curvature drop).
    #[arg(long)]
    pub flat_earth: bool,
    /// Draw the tiles as clusters of up to 16 neighbours, one draw call
    /// each (Judnich & Ling), instead of one draw call per tile.
    #[arg(long)]
    pub clusters: bool,
    /// PNG snapshots written along a headless flight (the last frame always is).
    #[arg(long, default_value_t = 6)]
    pub snapshots: u32,
    /// Ridgeline's own memory, MB (its heap and its GPU buffers, headless
    /// snapshots included): sizes the node atlas (counted in bytes), the
    /// loader, the staging copy and the GPU buffer at start. A budget too
    /// small for the view draws coarser data, never holes, and the summary
    /// and stats.json say the bound was loosened. 0: no budget, sized for
    /// the view (every atlas slot holds the largest node; 276 MB on the
    /// default flight).
    #[arg(long, default_value_t = 64)]
    pub memory_mb: u32,
    /// Fly live from UDP: KIND:[ADDR:]PORT, KIND `flightgear` (FlightGear's
    /// or JSBSim's native FDM packet), `xplane` (RPOS, or DATA groups 17
    /// and 20) or `gdl90` (ownship and AHRS: Stratux, ForeFlight); ADDR
    /// 127.0.0.1 unless given (0.0.0.0 listens on every interface).
    #[arg(long)]
    pub input: Option<InputSpec>,
    /// Live: withdraw the terrain and show the failure flag when no valid
    /// sample has come for this many milliseconds.
    #[arg(long, default_value_t = 1000)]
    pub stale_ms: u64,
    /// Live, headless: frames a second (`--frames` of them are drawn);
    /// in a window, the most frames a second.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Live: write the poses received to this CSV in the `--path` format,
    /// so the flight replays.
    #[arg(long, requires = "input")]
    pub record: Option<PathBuf>,
    /// The reference symbols over the terrain: zero-pitch line with heading
    /// marks, aircraft symbol, flight path marker.
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub symbology: Switch,
    /// Live GDL 90: the geoid's height above the WGS 84 ellipsoid where
    /// you fly, metres, taken off the ellipsoidal geometric altitude the
    /// GDL 90 ICD specifies (about +28 m over eastern Turkey, -30 m over
    /// the US Midwest). Not needed when the box says its altitude is MSL.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub geoid_m: f64,
    /// Live X-Plane: ask X-Plane at HOST:PORT (its port is 49000) to
    /// stream RPOS to the `--input` port, and again while none comes.
    #[arg(long, requires = "input")]
    pub xplane_host: Option<std::net::SocketAddr>,
}

/// On or off.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    /// On.
    On,
    /// Off.
    Off,
}

impl Switch {
    /// Whether it is on.
    pub fn on(self) -> bool {
        self == Switch::On
    }
}
