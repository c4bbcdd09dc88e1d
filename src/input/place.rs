//! The one conversion from the live pose record (geodetic) to the
//! display's frame, and back: today the dataset's local equirectangular
//! frame ([`crate::flight::geographic`]). When the display moves onto the
//! WGS 84 ellipsoid, this file is what changes.

use glam::{DVec2, DVec3};

use super::pose::GeoPose;
use crate::flight::{Equirectangular, Pose};
use crate::geo::{Crs, GeoRef};

/// Where live poses land on a dataset's display.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DisplayFrame {
    frame: Equirectangular,
}

/// A dataset live input cannot be placed on.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("live input needs a dataset in longitude/latitude (this one is {0:?}): a pose in degrees has nowhere to go")]
pub struct NotGeographic(pub Crs);

impl DisplayFrame {
    /// The frame of a dataset with `georef` and `posts` posts east and north.
    pub fn new(georef: &GeoRef, posts: [u32; 2]) -> Result<DisplayFrame, NotGeographic> {
        match georef.crs {
            Crs::Geographic => Ok(DisplayFrame { frame: Equirectangular::new(georef, posts) }),
            crs => Err(NotGeographic(crs)),
        }
    }

    /// The display pose of `pose`.
    pub fn pose(&self, pose: &GeoPose) -> Pose {
        let horizontal = self.frame.to_local(pose.lat_deg, pose.lon_deg);
        Pose {
            position: horizontal.extend(pose.alt_m),
            heading_deg: pose.heading_deg,
            pitch_deg: pose.pitch_deg,
            roll_deg: pose.roll_deg,
        }
    }

    /// A velocity north, east, down as a vector of the display's frame
    /// (x east, y north, z up). The equirectangular frame keeps directions
    /// to within its scale error (0.4 % across a 1° tile).
    pub fn velocity(&self, ned: [f64; 3]) -> DVec3 {
        DVec3::new(ned[1], ned[0], -ned[2])
    }

    /// The geodetic pose of a display pose.
    pub fn geodetic(&self, pose: &Pose) -> GeoPose {
        let at = self.frame.to_geographic(DVec2::new(pose.position.x, pose.position.y));
        GeoPose {
            lat_deg: at.lat,
            lon_deg: at.lon,
            alt_m: pose.position.z,
            heading_deg: pose.heading_deg,
            pitch_deg: pose.pitch_deg,
            roll_deg: pose.roll_deg,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_go_there_and_back() {
        let georef =
            GeoRef { crs: Crs::Geographic, origin: [40.0, 39.0], spacing: [1.0 / 1200.0; 2] };
        let frame = DisplayFrame::new(&georef, [1201, 1201]).unwrap();
        let pose = GeoPose {
            lat_deg: 39.5,
            lon_deg: 40.25,
            alt_m: 3000.0,
            heading_deg: 10.0,
            pitch_deg: -3.0,
            roll_deg: 5.0,
        };
        let local = frame.pose(&pose);
        assert!(local.position.x > 20_000.0 && local.position.y > 55_000.0, "{local:?}");
        let back = frame.geodetic(&local);
        assert!((back.lat_deg - 39.5).abs() < 1e-12 && (back.lon_deg - 40.25).abs() < 1e-12);
        assert!(DisplayFrame::new(&GeoRef::local([30.0; 2]), [10, 10]).is_err());
    }
}
