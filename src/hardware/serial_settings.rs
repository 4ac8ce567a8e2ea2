//! A serial line's settings as one table: the Hardware page's Serial port fields (what WebSerial
//! opens the port with) and `cutlab host --baud` are its rows, parsed by [`parse_serial`].

use crate::input::table::{Kind, Reader, Row, RowError, Shown, Table};

/// Every setting of a serial line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SerialSetting {
    /// Bits per second.
    Baud,
    /// Data bits per character.
    DataBits,
    /// The parity bit.
    Parity,
    /// Stop bits per character.
    StopBits,
    /// Flow control.
    FlowControl,
    /// The browser's read buffer.
    Buffer,
}

impl Table for SerialSetting {
    const ROWS: &'static [Self] = &[
        SerialSetting::Baud,
        SerialSetting::DataBits,
        SerialSetting::Parity,
        SerialSetting::StopBits,
        SerialSetting::FlowControl,
        SerialSetting::Buffer,
    ];

    fn row(self) -> Row {
        use SerialSetting as S;
        match self {
            S::Baud => Row::new("baud", "baud", "Baud rate", "bit/s")
                .takes(
                    Kind::Count {
                        min: 300,
                        max: 16_000_000,
                    },
                    Shown::Count(921_600),
                )
                .help("the line's speed"),
            S::DataBits => Row::new("data_bits", "", "Data bits", "")
                .takes(Kind::Choice, Shown::Choice("8"))
                .noun("data bits")
                .help("data bits per character"),
            S::Parity => Row::new("parity", "", "Parity", "")
                .takes(Kind::Choice, Shown::Choice("none"))
                .noun("parity")
                .help("the parity bit"),
            S::StopBits => Row::new("stop_bits", "", "Stop bits", "")
                .takes(Kind::Choice, Shown::Choice("1"))
                .noun("stop bits")
                .help("stop bits per character"),
            S::FlowControl => Row::new("flow", "", "Flow control", "")
                .takes(Kind::Choice, Shown::Choice("none"))
                .noun("flow control")
                .help("flow control"),
            S::Buffer => Row::new("buffer", "", "Read buffer", "bytes")
                .takes(
                    Kind::Count {
                        min: 255,
                        max: 16_777_216,
                    },
                    Shown::Count(4096),
                )
                .help("the browser's read buffer: at least one frame of 255 bytes"),
        }
    }

    fn choices(self) -> Vec<(&'static str, &'static str)> {
        match self {
            SerialSetting::DataBits => vec![("8", "8"), ("7", "7")],
            SerialSetting::Parity => vec![("none", "none"), ("even", "even"), ("odd", "odd")],
            SerialSetting::StopBits => vec![("1", "1"), ("2", "2")],
            SerialSetting::FlowControl => {
                vec![("none", "none"), ("hardware", "hardware (RTS/CTS)")]
            }
            _ => Vec::new(),
        }
    }
}

/// A serial line as asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SerialSettings {
    /// Bits per second.
    pub baud_rate: u32,
    /// 7 or 8.
    pub data_bits: u8,
    /// 1 or 2.
    pub stop_bits: u8,
    /// "none", "even" or "odd".
    pub parity: &'static str,
    /// "none" or "hardware".
    pub flow_control: &'static str,
    /// The browser's read buffer, bytes.
    pub buffer_size: u32,
}

/// Parses the typed text of a serial line's settings (those not given take their defaults).
///
/// ```
/// use cutlab::hardware::serial_settings::{parse_serial, SerialSetting};
/// let line = parse_serial(&[(SerialSetting::Baud, "460800"), (SerialSetting::Parity, "even")]).unwrap();
/// assert_eq!((line.baud_rate, line.parity, line.data_bits), (460_800, "even", 8));
/// let e = parse_serial(&[(SerialSetting::Baud, "100")]).unwrap_err();
/// assert_eq!(e[0].for_cli(), "--baud: 100 bit/s is outside 300–1.6e7 bit/s");
/// ```
pub fn parse_serial<T: AsRef<str>>(
    texts: &[(SerialSetting, T)],
) -> Result<SerialSettings, Vec<RowError<SerialSetting>>> {
    let mut reader = Reader::new(texts);
    let baud = reader.count(SerialSetting::Baud);
    let data_bits = reader.choice(SerialSetting::DataBits);
    let parity = reader.choice(SerialSetting::Parity);
    let stop_bits = reader.choice(SerialSetting::StopBits);
    let flow = reader.choice(SerialSetting::FlowControl);
    let buffer = reader.count(SerialSetting::Buffer);
    let line = match (baud, data_bits, parity, stop_bits, flow, buffer) {
        (Some(baud), Some(data), Some(parity), Some(stop), Some(flow), Some(buffer)) => {
            // The rows' ranges and choices fit these types.
            Some(SerialSettings {
                baud_rate: u32::try_from(baud).unwrap_or(u32::MAX),
                data_bits: if data == "7" { 7 } else { 8 },
                stop_bits: if stop == "2" { 2 } else { 1 },
                parity,
                flow_control: flow,
                buffer_size: u32::try_from(buffer).unwrap_or(u32::MAX),
            })
        }
        _ => None,
    };
    reader.finish(line)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::check_table;

    #[test]
    fn the_table_holds_and_its_defaults_are_a_fast_line() {
        assert_eq!(check_table::<SerialSetting>(), Ok(()));
        let line = parse_serial::<&str>(&[]).unwrap();
        assert_eq!(
            line,
            SerialSettings {
                baud_rate: 921_600,
                data_bits: 8,
                stop_bits: 1,
                parity: "none",
                flow_control: "none",
                buffer_size: 4096,
            }
        );
    }
}
