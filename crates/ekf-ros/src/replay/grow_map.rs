//! `ekf replay --grow-map`: the map keeps growing as the robot explores. Each key scan
//! (`[slam] key_distance` / `key_angle` from the last) adds its lines, placed at the
//! filter's pose, to a [`MapBuilder`] that fuses repeated sightings, and the filter
//! localizes in the grown map from then on. Without loop closures the walls of a place
//! first seen with an error keep it; `ekf map build --slam` closes loops.

use super::{ReplayError, ScanHook};
use crate::slam_config::SlamParams;
use ekf_core::Pose2;
use ekf_fusion::{Fuser, Scan, ScanFused};
use lrf_lines::{LineMap, LocalizerError, MapBuilder};

/// The growing map (a [`ScanHook`]).
#[derive(Debug, Clone)]
pub struct MapGrowth {
    params: SlamParams,
    builder: MapBuilder,
    last_key: Option<Pose2<f64>>,
    key_scans: u64,
}

impl MapGrowth {
    /// An empty map, grown with `params` (key scan spacing, wall fusion). Fails on
    /// invalid map builder parameters.
    pub fn new(params: &SlamParams) -> Result<Self, ReplayError> {
        let builder = MapBuilder::new(params.map_builder)
            .map_err(|e| ReplayError::Filter(LocalizerError::Filter(e)))?;
        Ok(Self {
            params: *params,
            builder,
            last_key: None,
            key_scans: 0,
        })
    }

    /// The map grown so far.
    pub fn map(&self) -> LineMap {
        self.builder.clone().finish()
    }

    /// Key scans that added their lines.
    pub fn key_scans(&self) -> u64 {
        self.key_scans
    }
}

impl ScanHook for MapGrowth {
    fn scan_fused(
        &mut self,
        _now: u64,
        _fused: &ScanFused,
        _scan: &Scan,
        fuser: &mut Fuser,
    ) -> Result<bool, ReplayError> {
        let filter = fuser.localizer();
        let pose = filter.pose();
        if filter.last_lines().is_empty()
            || self
                .last_key
                .is_some_and(|last| !self.params.is_key(&last, &pose))
        {
            return Ok(false);
        }
        let sensor = pose.compose(&filter.config().laser_mount);
        self.builder
            .add_scan(filter.last_lines(), &sensor)
            .map_err(|e| ReplayError::Filter(LocalizerError::Filter(e)))?;
        self.last_key = Some(pose);
        self.key_scans += 1;
        let map = self.map();
        fuser.localizer_mut().replace_map(map);
        Ok(true)
    }
}
