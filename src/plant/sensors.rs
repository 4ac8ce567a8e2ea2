//! Current sensors: Hall-effect transducer, burden resistor, analogue band limit, ADC.
//!
//! Paper 000 measures the servo motor's phase currents with HYH-SB-13-10A Hall sensors: a
//! strictly linear current transformer whose output is 25 mA at its 6 A maximum input, turned
//! into a voltage by a 500 Ω sampling resistor R_m, "DC to 1000 Hz". Paper 003 passes its Hall
//! signals through analogue low-passes (50 Hz feed, 260 Hz spindle) before an AD2200 converter.
//! cutlab models one phase as
//!
//! ```text
//! i_s = i·(1 + gain error) + offset                      what the transducer sees
//! u   = lag(i_s·(I_out/I_in)·R_m) + noise                volts at the ADC input
//! u_q = LSB·round(clamp(u, ±range)/LSB)                   ADC, LSB = 2·range/2^bits
//! i_read = u_q / ((I_out/I_in)·R_m)                       converted back with the nominal scale
//! ```
//!
//! so gain and offset errors, noise, saturation and quantisation all appear in the reading the
//! way they would on a bench. With [`PhaseWiring::TwoPhases`] (paper 000 threads "either two
//! phase" conductors through its sensors; paper 003 measures U and V) the third phase is computed
//! as −(i_u + i_v), carrying both sensors' errors.
//!
//! Every noise source draws from its own seeded [`Rng`] stream. A NaN current reads as NaN (a
//! clamp would hide a broken model); ±∞ saturates at the ADC range.

use serde::{Deserialize, Serialize};

use super::dynamics::FirstOrderLag;
use super::{finite, in_range, non_negative, positive, PlantError};
use crate::rng::{Normal, Rng};

/// A Hall-effect current transducer with its burden resistor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HallSensorConfig {
    /// Primary current at which the secondary gives `rated_output_ma`. Paper 000: 6 A.
    pub rated_input_a: f64,
    /// Secondary current at the rated input. Paper 000: 25 mA.
    pub rated_output_ma: f64,
    /// Burden (sampling) resistor R_m. Paper 000: 500 Ω.
    pub burden_ohm: f64,
    /// Bandwidth of transducer plus any analogue filter (first order). Paper 000: 1000 Hz.
    pub bandwidth_hz: f64,
    /// Relative gain error of the transducer (0.01 reads 1 % high). Default 0.
    pub gain_error: f64,
    /// Offset of each phase's transducer, in primary amperes.
    pub offsets_a: [f64; 3],
    /// RMS noise at the ADC input, in primary amperes.
    pub noise_a: f64,
}

impl HallSensorConfig {
    /// Paper 000's feed-motor sensor: 6 A → 25 mA into 500 Ω, DC–1 kHz; small offsets and
    /// 5 mA noise (chosen).
    pub fn paper_000_feed() -> Self {
        Self {
            rated_input_a: 6.0,
            rated_output_ma: 25.0,
            burden_ohm: 500.0,
            bandwidth_hz: 1000.0,
            gain_error: 0.0,
            offsets_a: [0.004, -0.003, 0.002],
            noise_a: 0.005,
        }
    }

    /// A spindle-motor sensor of the same family for larger currents (chosen): 50 A → 25 mA into
    /// 150 Ω (7.5 V at 50 A, ±66 A before a ±10 V ADC saturates), 1 kHz, 50 mA noise.
    pub fn spindle() -> Self {
        Self {
            rated_input_a: 50.0,
            rated_output_ma: 25.0,
            burden_ohm: 150.0,
            bandwidth_hz: 1000.0,
            gain_error: 0.0,
            offsets_a: [0.03, -0.02, 0.01],
            noise_a: 0.05,
        }
    }

    /// Volts at the burden per primary ampere, (I_out/I_in)·R_m.
    ///
    /// ```
    /// use cutlab::plant::sensors::HallSensorConfig;
    /// // Paper 000: 6 A → 25 mA into 500 Ω is 12.5 V at 6 A.
    /// assert!((HallSensorConfig::paper_000_feed().volts_per_amp() * 6.0 - 12.5).abs() < 1e-12);
    /// ```
    pub fn volts_per_amp(&self) -> f64 {
        self.rated_output_ma * 1e-3 / self.rated_input_a * self.burden_ohm
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("rated_input_a", self.rated_input_a)?;
        positive("rated_output_ma", self.rated_output_ma)?;
        positive("burden_ohm", self.burden_ohm)?;
        non_negative("bandwidth_hz", self.bandwidth_hz)?;
        in_range("gain_error", self.gain_error, -0.5, 0.5)?;
        for (i, o) in self.offsets_a.iter().enumerate() {
            finite(&format!("offsets_a[{i}]"), *o)?;
        }
        non_negative("noise_a", self.noise_a)?;
        Ok(())
    }
}

/// The analogue-to-digital converter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdcConfig {
    /// Resolution. Default 12 bits (chosen; paper 003's AD2200 class).
    pub bits: u32,
    /// Bipolar input range ±range. Default 10 V.
    pub range_v: f64,
}

impl Default for AdcConfig {
    fn default() -> Self {
        Self {
            bits: 12,
            range_v: 10.0,
        }
    }
}

impl AdcConfig {
    /// One least significant bit in volts, 2·range/2^bits.
    ///
    /// ```
    /// use cutlab::plant::sensors::AdcConfig;
    /// assert!((AdcConfig::default().lsb_v() - 20.0 / 4096.0).abs() < 1e-15);
    /// ```
    pub fn lsb_v(&self) -> f64 {
        2.0 * self.range_v / f64::from(1u32 << self.bits)
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        if !(4..=24).contains(&self.bits) {
            return Err(PlantError::new(
                "bits",
                format!("must lie in 4..=24, got {}", self.bits),
            ));
        }
        positive("range_v", self.range_v)?;
        Ok(())
    }

    /// Quantises a voltage: clamps to the range and rounds to the nearest code (ties to the even
    /// code).
    ///
    /// ```
    /// use cutlab::plant::sensors::AdcConfig;
    /// let adc = AdcConfig { bits: 4, range_v: 8.0 }; // 1 V steps, codes −8…7
    /// assert_eq!(adc.quantise(2.4), 2.0);
    /// assert_eq!(adc.quantise(100.0), 7.0);
    /// assert_eq!(adc.quantise(-100.0), -8.0);
    /// ```
    pub fn quantise(&self, volts: f64) -> f64 {
        Quantiser::new(self).code(volts) * self.lsb_v()
    }
}

/// An ADC's quantisation with its constants worked out once: the code of a voltage.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Quantiser {
    codes_per_volt: f64,
    lowest_code: f64,
    highest_code: f64,
}

impl Quantiser {
    fn new(adc: &AdcConfig) -> Self {
        let half = f64::from(1u32 << (adc.bits - 1));
        Self {
            codes_per_volt: 1.0 / adc.lsb_v(),
            lowest_code: -half,
            highest_code: half - 1.0,
        }
    }

    /// The code of `volts`, clamped to the range (NaN stays NaN: a broken model must show).
    /// The bounds are whole codes, so clamping before rounding equals clamping after.
    #[inline(always)]
    fn code(&self, volts: f64) -> f64 {
        crate::math::round_ties_even(crate::math::clamp(
            volts * self.codes_per_volt,
            self.lowest_code,
            self.highest_code,
        ))
    }
}

/// Which phases carry a sensor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PhaseWiring {
    /// U and V are measured; W = −(U + V).
    TwoPhases,
    /// All three are measured.
    ThreePhases,
}

impl PhaseWiring {
    /// Both wirings.
    pub const ALL: [PhaseWiring; 2] = [PhaseWiring::TwoPhases, PhaseWiring::ThreePhases];

    /// Label for forms.
    pub fn label(self) -> &'static str {
        match self {
            PhaseWiring::TwoPhases => "U and V measured, W = −(U + V)",
            PhaseWiring::ThreePhases => "U, V and W measured",
        }
    }
}

/// A three-phase current measurement channel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurrentSensorConfig {
    /// The transducer.
    pub hall: HallSensorConfig,
    /// The converter.
    pub adc: AdcConfig,
    /// Which phases are measured.
    pub wiring: PhaseWiring,
}

impl CurrentSensorConfig {
    /// Paper 000's feed-motor channel: two Hall sensors, ±10 V 12-bit ADC.
    pub fn feed() -> Self {
        Self {
            hall: HallSensorConfig::paper_000_feed(),
            adc: AdcConfig::default(),
            wiring: PhaseWiring::TwoPhases,
        }
    }

    /// The spindle channel (paper 003 measures U and V).
    pub fn spindle() -> Self {
        Self {
            hall: HallSensorConfig::spindle(),
            adc: AdcConfig::default(),
            wiring: PhaseWiring::TwoPhases,
        }
    }

    /// An ideal channel (no error, no noise, 24-bit, wide range) for tests.
    pub fn ideal(rated_input_a: f64) -> Self {
        Self {
            hall: HallSensorConfig {
                rated_input_a,
                rated_output_ma: 25.0,
                burden_ohm: 200.0,
                bandwidth_hz: 0.0,
                gain_error: 0.0,
                offsets_a: [0.0; 3],
                noise_a: 0.0,
            },
            adc: AdcConfig {
                bits: 24,
                range_v: 10.0,
            },
            wiring: PhaseWiring::ThreePhases,
        }
    }

    /// The largest current the channel reads before the ADC saturates.
    ///
    /// ```
    /// use cutlab::plant::sensors::CurrentSensorConfig;
    /// assert!((CurrentSensorConfig::feed().full_scale_a() - 4.8).abs() < 1e-12);
    /// ```
    pub fn full_scale_a(&self) -> f64 {
        self.adc.range_v / self.hall.volts_per_amp()
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        self.hall.validate().map_err(|e| e.within("hall"))?;
        self.adc.validate().map_err(|e| e.within("adc"))?;
        Ok(())
    }
}

/// A running three-phase current channel.
///
/// ```
/// use cutlab::plant::sensors::{CurrentSensor, CurrentSensorConfig};
/// let mut s = CurrentSensor::new(CurrentSensorConfig::feed(), 1e-4, 7, 0).unwrap();
/// let mut read = [0.0; 3];
/// for _ in 0..50 { read = s.read([1.0, -0.5, -0.5]); } // past the 1 kHz band limit's rise
/// assert!((read[0] - 1.0).abs() < 0.05); // offset, noise and a 2.3 mA LSB
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CurrentSensor {
    config: CurrentSensorConfig,
    lags: [FirstOrderLag; 3],
    rngs: [Rng; 3],
    normal: Normal,
    /// Phases with a sensor of their own: 2 (U, V) or 3.
    measured: usize,
    /// Volts at the ADC per primary ampere, gain error included: (1 + e)·(I_out/I_in)·R_m.
    seen_v_per_a: f64,
    /// Each phase's offset, in volts at the ADC.
    offsets_v: [f64; 3],
    /// RMS noise in volts at the ADC (0: no draw).
    noise_v: f64,
    quantiser: Quantiser,
    /// Amperes per ADC code with the nominal scale: LSB/((I_out/I_in)·R_m).
    amps_per_code: f64,
}

impl CurrentSensor {
    /// A channel sampled every `dt_s`, its three noise streams forked from `seed` at streams
    /// `first_stream`, `first_stream + 1`, `first_stream + 2`.
    pub fn new(
        config: CurrentSensorConfig,
        dt_s: f64,
        seed: u64,
        first_stream: u64,
    ) -> Result<Self, PlantError> {
        config.validate()?;
        positive("dt_s", dt_s)?;
        let lag = FirstOrderLag::new(config.hall.bandwidth_hz, dt_s);
        let hall = &config.hall;
        let volts_per_amp = hall.volts_per_amp();
        Ok(Self {
            config,
            lags: [lag; 3],
            rngs: [0, 1, 2].map(|k| Rng::fork(seed, first_stream + k)),
            normal: Normal::new(),
            measured: match config.wiring {
                PhaseWiring::TwoPhases => 2,
                PhaseWiring::ThreePhases => 3,
            },
            seen_v_per_a: (1.0 + hall.gain_error) * volts_per_amp,
            offsets_v: hall.offsets_a.map(|o| o * volts_per_amp),
            noise_v: hall.noise_a * volts_per_amp,
            quantiser: Quantiser::new(&config.adc),
            amps_per_code: config.adc.lsb_v() / volts_per_amp,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &CurrentSensorConfig {
        &self.config
    }

    /// Samples the true phase currents; returns what the ADC reads, in amperes.
    #[inline(always)]
    pub fn read(&mut self, currents_a: [f64; 3]) -> [f64; 3] {
        // The wiring never changes in a run: one branch here, and each loop below has a count
        // the compiler knows (unrolled, no bounds checks).
        if self.measured == 2 {
            self.read_phases::<2>(currents_a)
        } else {
            self.read_phases::<3>(currents_a)
        }
    }

    /// [`CurrentSensor::read`] of each sample of `currents_a` in turn, the reading replacing
    /// the true currents: the same bits as reading them one by one. A simulation reads a
    /// block's samples together after the block's physics, since nothing there depends on
    /// them; each phase keeps its own lag and noise stream, so a sample's phases are
    /// independent chains, stepped side by side.
    #[inline(always)]
    pub fn read_block(&mut self, currents_a: &mut [[f64; 3]]) {
        // One branch on the wiring per block, as `read` does per sample.
        if self.measured == 2 {
            for sample in currents_a.iter_mut() {
                *sample = self.read_phases::<2>(*sample);
            }
        } else {
            for sample in currents_a.iter_mut() {
                *sample = self.read_phases::<3>(*sample);
            }
        }
    }

    /// [`CurrentSensor::read`] with `MEASURED` (2 or 3) phases measured.
    #[inline(always)]
    fn read_phases<const MEASURED: usize>(&mut self, currents_a: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        // Each phase draws from its own stream, so an unmeasured phase (W in two-phase wiring)
        // need not draw at all: the others' noise is the same either way.
        for k in 0..MEASURED {
            let noise_v = if self.noise_v == 0.0 {
                0.0
            } else {
                self.noise_v * self.normal.sample(&mut self.rngs[k])
            };
            let seen_v = currents_a[k] * self.seen_v_per_a + self.offsets_v[k];
            let volts = self.lags[k].step(seen_v) + noise_v;
            out[k] = self.quantiser.code(volts) * self.amps_per_code;
        }
        if MEASURED == 2 {
            out[2] = -(out[0] + out[1]);
        }
        out
    }

    /// Back to the start: lags at rest, noise streams restarted from `seed`.
    pub fn reset(&mut self, seed: u64, first_stream: u64) {
        for lag in self.lags.iter_mut() {
            lag.reset(0.0);
        }
        self.rngs = [0, 1, 2].map(|k| Rng::fork(seed, first_stream + k));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ideal_channel_reads_the_truth_to_the_lsb() {
        let cfg = CurrentSensorConfig::ideal(10.0);
        let mut s = CurrentSensor::new(cfg, 1e-4, 1, 0).unwrap();
        let read = s.read([3.0, -1.0, -2.0]);
        let lsb_a = cfg.adc.lsb_v() / cfg.hall.volts_per_amp();
        for (r, t) in read.iter().zip([3.0, -1.0, -2.0]) {
            assert!((r - t).abs() <= 0.5 * lsb_a + 1e-15);
        }
    }

    #[test]
    fn saturates_at_the_adc_range() {
        let cfg = CurrentSensorConfig::feed();
        let mut s = CurrentSensor::new(cfg, 1e-4, 1, 0).unwrap();
        let mut r = [0.0; 3];
        for _ in 0..100 {
            r = s.read([50.0, -25.0, -25.0]);
        }
        // Paper 000's 500 Ω burden clips a ±10 V ADC at 4.8 A.
        assert!((r[0] - cfg.full_scale_a()).abs() < 0.02, "{r:?}");
        assert!((cfg.full_scale_a() - 4.8).abs() < 1e-12);
    }

    #[test]
    fn gain_error_and_offset_show_in_the_reading() {
        let mut cfg = CurrentSensorConfig::ideal(10.0);
        cfg.hall.gain_error = 0.02;
        cfg.hall.offsets_a = [0.1, 0.0, 0.0];
        let mut s = CurrentSensor::new(cfg, 1e-4, 1, 0).unwrap();
        let r = s.read([2.0, 0.0, 0.0]);
        assert!((r[0] - (2.0 * 1.02 + 0.1)).abs() < 1e-5);
    }

    #[test]
    fn same_seed_same_noise_and_streams_are_independent() {
        let cfg = CurrentSensorConfig::feed();
        let mut a = CurrentSensor::new(cfg, 1e-4, 9, 0).unwrap();
        let mut b = CurrentSensor::new(cfg, 1e-4, 9, 0).unwrap();
        let mut c = CurrentSensor::new(cfg, 1e-4, 9, 10).unwrap();
        let ra = a.read([1.0, 0.0, -1.0]);
        assert_eq!(ra, b.read([1.0, 0.0, -1.0]));
        assert_ne!(ra, c.read([1.0, 0.0, -1.0]));
    }

    #[test]
    fn two_phase_wiring_computes_the_third() {
        let mut s = CurrentSensor::new(CurrentSensorConfig::feed(), 1e-4, 3, 0).unwrap();
        let r = s.read([1.0, -0.4, -0.6]);
        assert_eq!(r[2], -(r[0] + r[1]));
    }
}
