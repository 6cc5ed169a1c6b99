//! `ekf`: localization from wheel odometry, a compass and laser lines. See `ekf --help`.

fn main() {}
