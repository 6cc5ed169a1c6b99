//! The state of an `ekf live` run: the readings held back until they can be fused in the
//! order they were made, the filter loop they are fused by, the recording, and the
//! counts.

use super::clock::Clock;
use super::messages::{self, Recorder};
use super::report::{LiveError, LiveOutcome, LiveSummary};
use super::workers::{self, Data, DeviceCounters};
use super::{
    LiveEvent, LiveOptions, DEVICE_DIAGNOSTICS_TOPIC, FIX_TOPIC, HOLD_SLACK, RECORDING_CHUNK_NS,
};
use crate::devices::modbus_base::{BaseReading, EncoderTracker, WheelTicks};
use crate::devices::sick::Variant;
use ekf_fusion::{Forecast, Reorder};
use ekf_ros::config::Config;
use ekf_ros::replay::{Preamble, ReplayOptions, ReplaySummary, Run};
use ekf_ros::ros2::builtin_interfaces::Time;
use ekf_ros::ros2::diagnostic_msgs::{DiagnosticArray, DiagnosticStatus, KeyValue};
use ekf_ros::ros2::std_msgs::Header;
use ekf_ros::ros2::AnyMessage;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

/// The wheel positions from the base controller's reads, across reconnections.
#[derive(Debug, Clone)]
pub(super) struct BaseTicks {
    tracker: EncoderTracker,
    /// The base worker's connection the tracker follows.
    connection: u64,
}

impl BaseTicks {
    /// The wheel positions after `reading`, made at `t_ns` and received on the base
    /// worker's connection `connection` ([`EncoderTracker::update`]). After a new
    /// connection the first read tells whether the controller counted on while the line
    /// was down (the motion of the outage is kept) or restarted (a new reference).
    fn update(&mut self, reading: BaseReading, connection: u64, t_ns: u64) -> Option<WheelTicks> {
        if connection != self.connection {
            self.tracker.reconnected();
            self.connection = connection;
        }
        self.tracker.update(reading, t_ns)
    }
}

/// The main loop's state.
pub(super) struct Live<'a> {
    config: &'a Config,
    run: Run<'a>,
    recorder: Recorder,
    clock: Clock,
    base: BaseTicks,
    variant: Variant,
    counters: BTreeMap<&'static str, DeviceCounters>,
    pub(super) summary: LiveSummary,
    /// Measurements held back until none made before them can still arrive, by the
    /// stamp of when they were made (ties in the order they came): a measurement is
    /// fused once the clock is past its stamp by the hold, the largest device latency
    /// plus [`HOLD_SLACK`] — the rule by which replay fuses an input once one stamped
    /// `max_lag` later has come, with the clock's now as that input.
    pending: Reorder<Data>,
    /// Stamp of the last message fused (at first the recording's start).
    last_ns: u64,
    /// Time of the last pose reported (0: none yet).
    reported_ns: u64,
}

impl<'a> Live<'a> {
    pub(super) fn new(
        config: &'a Config,
        options: &LiveOptions,
        variant: Variant,
        clock: Clock,
    ) -> Result<Self, LiveError> {
        let t0 = clock.stamp(clock.started);
        let tf = messages::laser_transform(config, t0);
        let preamble = Preamble {
            scan_frame: Some(config.devices.laser_frame.clone()),
            transforms: tf.transforms.clone(),
            first_reference: None,
        };
        let replay_options = ReplayOptions {
            mode: options.mode,
            map: options.map.clone(),
            init_from_truth: false,
            out_mcap: options.record.clone(),
            tum: None,
            keep_trajectories: false,
            global: false,
            grow_map: false,
        };
        let name = options
            .record
            .as_ref()
            .map_or_else(|| "live".into(), |p| p.display().to_string());
        let mut run = Run::start(
            config,
            &replay_options,
            &preamble,
            true,
            &name,
            &config.topics.joint_states,
            // The readings come in the order they were made (`hold_back`): each is fused
            // as it is handed on.
            0,
        )?;
        if let Some(out) = run.output() {
            out.writer().close_chunks_every(RECORDING_CHUNK_NS);
        }
        let mut recorder = Recorder::new(Path::new(&name));
        let at = recorder.record_at(run.output(), &config.topics.tf_static, t0, &tf)?;
        run.handle_decoded(&at.channel, at.log_time, at.log_time, tf.into())?;
        Ok(Self {
            config,
            run,
            recorder,
            clock,
            base: BaseTicks {
                tracker: EncoderTracker::new(
                    config.devices.max_wheel_turns_per_s * config.devices.ticks_per_revolution,
                ),
                connection: 0,
            },
            variant,
            counters: BTreeMap::new(),
            summary: LiveSummary {
                filter: ReplaySummary::default(),
                devices: BTreeMap::new(),
                reconnects: BTreeMap::new(),
                base_repeated_samples: 0,
                base_missed_samples: 0,
                base_implausible_samples: 0,
                base_outages_bridged: 0,
                base_restarts: 0,
                compass_invalid: 0,
                gps_fixes: 0,
                late_readings: 0,
                recording: options.record.as_ref().map(|p| p.display().to_string()),
            },
            pending: Reorder::new(HOLD_SLACK.as_nanos() as u64),
            last_ns: t0,
            reported_ns: 0,
        })
    }

    pub(super) fn counters(&mut self, c: DeviceCounters) {
        let name = match c {
            DeviceCounters::Laser(_) => "laser",
            DeviceCounters::Base(_) => "base",
            DeviceCounters::Gps(_) => "gps",
        };
        self.counters.insert(name, c);
    }

    /// Sets how long a measurement is held: the largest device latency `latency`, plus
    /// [`HOLD_SLACK`].
    pub(super) fn set_hold(&mut self, latency: Duration) {
        self.pending
            .set_lag_ns((latency + HOLD_SLACK).as_nanos() as u64);
    }

    /// Holds a measurement made at `at` back until those made before it have arrived;
    /// one made before a measurement already fused is late: counted and dropped (fusing
    /// or recording it out of order would make the replay differ). Returns whether it
    /// was kept.
    pub(super) fn hold_back(&mut self, at: Instant, data: Data) -> bool {
        let kept = self.pending.push(self.clock.stamp(at), data).is_ok();
        if !kept {
            self.summary.late_readings += 1;
        }
        kept
    }

    /// Fuses, oldest first, the held measurements whose turn has come by `now`.
    pub(super) fn release_until(&mut self, now: Instant) -> Result<(), LiveError> {
        self.pending.advance_to(self.clock.stamp(now));
        while let Some((t, data)) = self.pending.pop_ready() {
            self.reading(t, data)?;
        }
        Ok(())
    }

    /// Fuses every held measurement, oldest first (at the end of the run).
    pub(super) fn release_all(&mut self) -> Result<(), LiveError> {
        while let Some((t, data)) = self.pending.pop() {
            self.reading(t, data)?;
        }
        Ok(())
    }

    /// The stamp of a message about a measurement made at `t_ns`: strictly after the last
    /// one (messages never share a stamp, and the recording's order is the stamps').
    fn stamp(&mut self, t_ns: u64) -> u64 {
        self.last_ns = t_ns.max(self.last_ns + 1);
        self.last_ns
    }

    /// Reports the pose now ([`forecast`](Self::forecast)) if it is later than the last
    /// one reported. A prediction that fails is reported as a warning, not as the run's
    /// failure: fusing the same readings will tell whether the filter itself failed.
    pub(super) fn report_pose(&mut self, on_event: &mut dyn FnMut(LiveEvent)) {
        match self.forecast() {
            Ok(Some(f)) if f.t_ns > self.reported_ns => {
                self.reported_ns = f.t_ns;
                on_event(LiveEvent::Pose {
                    t_ns: f.t_ns,
                    fused_ns: f.fused_ns,
                    pose: f.pose,
                    covariance: f.covariance,
                });
            }
            Ok(_) => {}
            Err(e) => on_event(LiveEvent::Device {
                device: "filter",
                level: 1,
                text: format!("the pose could not be predicted ahead: {e}"),
            }),
        }
    }

    /// The pose now: the fused state predicted through the wheel readings held back
    /// ([`Run::forecast`]), each turned into the joint state fusing it will record (but
    /// for the nanosecond its stamp may be moved by to keep stamps apart).
    fn forecast(&self) -> Result<Option<Forecast>, LiveError> {
        let mut base = self.base.clone();
        let joint_states: Vec<_> = self
            .pending
            .held()
            .filter_map(|(t, data)| {
                let Data::Base {
                    reading,
                    connection,
                } = data
                else {
                    return None;
                };
                let ticks = base.update(*reading, *connection, t)?;
                Some(messages::joint_state(self.config, t, ticks))
            })
            .collect();
        Ok(self.run.forecast(&joint_states)?)
    }

    fn reading(&mut self, at: u64, data: Data) -> Result<(), LiveError> {
        let topics = &self.config.topics;
        match data {
            Data::Scan { ranges, unit } => {
                let t = self.stamp(at);
                let scan = messages::laser_scan(self.config, self.variant, unit, t, ranges);
                self.feed(&topics.scan.clone(), scan)?;
            }
            Data::Base {
                reading: r,
                connection,
            } => {
                let Some(ticks) = self.base.update(r, connection, at) else {
                    return Ok(());
                };
                let t = self.stamp(at);
                let joints = messages::joint_state(self.config, t, ticks);
                self.feed(&topics.joint_states.clone(), joints)?;
                match r.bearing() {
                    Some(bearing) => {
                        let t = self.stamp(at);
                        let field = messages::compass(self.config, t, bearing);
                        self.feed(&topics.compass.clone(), field)?;
                    }
                    None => self.summary.compass_invalid += 1,
                }
            }
            Data::Fix(f) => {
                let t = self.stamp(at);
                let fix = f.to_nav_sat_fix(t, &self.config.devices.gps_frame);
                self.summary.gps_fixes += 1;
                self.feed(FIX_TOPIC, fix)?;
            }
        }
        Ok(())
    }

    /// Records a message and runs the filter on it as it is (no encoding unless it is
    /// recorded, no decoding): its stamp is its log time, so replaying the recording
    /// fuses it at the same time.
    fn feed<M>(&mut self, topic: &str, message: M) -> Result<(), LiveError>
    where
        M: ekf_ros::ros2::RosMessage + ekf_ros::ros2::Stamped + Into<AnyMessage>,
    {
        let at = self.recorder.record(self.run.output(), topic, &message)?;
        self.run
            .handle_decoded(&at.channel, at.log_time, at.log_time, message.into())?;
        Ok(())
    }

    pub(super) fn device_status(
        &mut self,
        device: &str,
        level: u8,
        text: &str,
    ) -> Result<(), LiveError> {
        self.diagnostics(vec![status(device, level, text, Vec::new())])
    }

    /// The encoder tracker's counts, into the summary.
    fn copy_base_counts(&mut self) {
        let t = &self.base.tracker;
        let s = &mut self.summary;
        s.base_repeated_samples = t.repeated;
        s.base_missed_samples = t.missed;
        s.base_implausible_samples = t.implausible;
        s.base_outages_bridged = t.outages_bridged;
        s.base_restarts = t.restarts;
    }

    /// Every device's counters as one diagnostics message.
    pub(super) fn counters_diagnostics(&mut self) -> Result<(), LiveError> {
        self.copy_base_counts();
        let statuses = self
            .counters
            .iter()
            .map(|(name, c)| {
                let values = match serde_json::to_value(c) {
                    Ok(serde_json::Value::Object(map)) => map
                        .into_iter()
                        .map(|(k, v)| KeyValue {
                            key: k,
                            value: v.to_string(),
                        })
                        .collect(),
                    _ => Vec::new(),
                };
                status(
                    name,
                    workers::OK,
                    "counters since the last connection",
                    values,
                )
            })
            .collect();
        self.diagnostics(statuses)
    }

    fn diagnostics(&mut self, statuses: Vec<DiagnosticStatus>) -> Result<(), LiveError> {
        let t = self.clock.now();
        let msg = DiagnosticArray {
            header: Header {
                stamp: Time::from_nanos(t).unwrap_or_default(),
                frame_id: String::new(),
            },
            status: statuses,
        };
        self.recorder
            .record(self.run.output(), DEVICE_DIAGNOSTICS_TOPIC, &msg)?;
        Ok(())
    }

    pub(super) fn finish(
        mut self,
        started: Instant,
        failure: Option<LiveError>,
    ) -> Result<LiveOutcome, LiveError> {
        self.copy_base_counts();
        let outcome = self.run.finish(started, None)?;
        self.summary.filter = outcome.summary;
        self.summary.devices = self
            .counters
            .iter()
            .map(|(k, v)| (*k, serde_json::to_value(v).unwrap_or_default()))
            .collect();
        Ok(LiveOutcome {
            summary: self.summary,
            failure,
        })
    }
}

fn status(device: &str, level: u8, text: &str, values: Vec<KeyValue>) -> DiagnosticStatus {
    DiagnosticStatus {
        level,
        name: format!("ekf/{device}"),
        message: text.into(),
        hardware_id: device.into(),
        values,
    }
}

#[cfg(test)]
mod forecast_tests {
    //! `Run::forecast` over the messages `ekf live` makes.
    use super::messages::{self, Recorder};
    use crate::devices::modbus_base::WheelTicks;
    use ekf_ros::config::Config;
    use ekf_ros::replay::{Mode, Preamble, ReplayOptions, Run};
    use ekf_ros::ros2::{AnyMessage, RosMessage, Stamped};
    use std::path::Path;

    fn run(config: &Config) -> Run<'_> {
        let options = ReplayOptions {
            mode: Mode::Compass,
            map: None,
            init_from_truth: false,
            out_mcap: None,
            tum: None,
            keep_trajectories: false,
            global: false,
            grow_map: false,
        };
        let preamble = Preamble {
            scan_frame: None,
            transforms: Vec::new(),
            first_reference: None,
        };
        let t = &config.topics.joint_states;
        Run::start(config, &options, &preamble, true, "test", t, 0).unwrap()
    }

    fn feed<M: RosMessage + Stamped + Clone + Into<AnyMessage>>(
        run: &mut Run<'_>,
        recorder: &mut Recorder,
        topic: &str,
        m: &M,
    ) {
        let at = recorder.record(None, topic, m).unwrap();
        run.handle_decoded(&at.channel, at.log_time, at.log_time, m.clone().into())
            .unwrap();
    }

    #[test]
    fn a_forecast_is_the_state_fusing_the_wheel_readings_would_give() {
        let config = Config::default();
        let (mut fused, mut all) = (run(&config), run(&config));
        let mut recorder = Recorder::new(Path::new("test"));
        // Wheel readings every 0.1 s of a robot turning left; a compass heading between
        // the second and third, so the third is predicted only over its last half.
        let joints: Vec<_> = (0..6)
            .map(|i| {
                let ticks = WheelTicks {
                    left: 40 * i,
                    right: 55 * i,
                };
                messages::joint_state(&config, 1_000_000_000 + i as u64 * 100_000_000, ticks)
            })
            .collect();
        // A bearing of 90° less a little: heading 0.02 rad, within the gate.
        let bearing = std::f64::consts::FRAC_PI_2 - 0.02;
        let heading = messages::compass(&config, 1_150_000_000, bearing);
        let (topic, compass) = (&config.topics.joint_states, &config.topics.compass);
        assert_eq!(fused.forecast(&joints).unwrap(), None, "nothing fused yet");
        for run in [&mut fused, &mut all] {
            feed(run, &mut recorder, topic, &joints[0]);
            feed(run, &mut recorder, topic, &joints[1]);
            feed(run, &mut recorder, compass, &heading);
        }
        for j in &joints[2..] {
            feed(&mut all, &mut recorder, topic, j);
        }
        assert_eq!(fused.fuser().counts().compass.accepted, 1);
        let before = *fused.filter().ekf();
        let forecast = fused.forecast(&joints[2..]).unwrap().unwrap();

        assert_eq!(
            *fused.filter().ekf(),
            before,
            "the filter is left as it was"
        );
        assert_eq!(forecast.fused_ns, 1_150_000_000);
        assert_eq!(forecast.t_ns, 1_500_000_000);
        assert_eq!(forecast.pose, all.filter().pose());
        assert_eq!(forecast.covariance, *all.filter().covariance());
        assert!(
            forecast.pose.theta > before.pose().theta + 0.01,
            "it turned"
        );
        // Nothing held back: the fused state at its own time.
        let now = fused.forecast(&[]).unwrap().unwrap();
        assert_eq!((now.t_ns, now.pose), (1_150_000_000, before.pose()));
    }
}
