//! The bytes each recorded pass binds: every storage buffer that a dispatch of the pass binds,
//! counted once per pass at its whole size, as read (bound read-only) or written (bound
//! read-write). Over a pass that touches each byte of its bindings once this is the traffic it
//! cannot do without; the benchmarks divide it by the device's bandwidth
//! ([`measure_bandwidth`](super::measure_bandwidth)) for the pass's byte floor.
//!
//! The log is kept per thread: a [`Recorder`](crate::passes::Recorder) begins one, names each
//! pass as it begins it, and takes the log when it finishes; dispatches recorded with no log
//! begun (outside a frame) are not counted.

use std::cell::RefCell;
use std::collections::HashMap;

/// The bytes one pass binds for reading and for writing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassTraffic {
    /// Stable pass name (as [`PassTiming::name`](super::PassTiming::name)).
    pub name: String,
    /// Bytes of the storage buffers bound read-only.
    pub read_bytes: u64,
    /// Bytes of the storage buffers bound read-write.
    pub written_bytes: u64,
}

/// Each pass's bound buffers (whether written), in the order the passes were first named, and
/// the pass being recorded.
#[derive(Default)]
struct Log {
    passes: Vec<(String, HashMap<wgpu::Buffer, bool>)>,
    current: Option<usize>,
}

thread_local! {
    static LOG: RefCell<Option<Log>> = const { RefCell::new(None) };
}

/// Begins a log on this thread (forgetting one left unfinished).
pub(crate) fn begin() {
    LOG.with(|l| *l.borrow_mut() = Some(Log::default()));
}

/// What is bound from now on belongs to the pass `name` (passes of one name are one entry).
pub(crate) fn pass(name: &str) {
    LOG.with(|l| {
        if let Some(log) = l.borrow_mut().as_mut() {
            let i = log.passes.iter().position(|(n, _)| n == name).unwrap_or_else(|| {
                log.passes.push((name.to_string(), HashMap::new()));
                log.passes.len() - 1
            });
            log.current = Some(i);
        }
    });
}

/// Notes that the current pass binds `buffer` (read-write when `written`).
pub(crate) fn bound(buffer: &wgpu::Buffer, written: bool) {
    LOG.with(|l| {
        if let Some(log) = l.borrow_mut().as_mut()
            && let Some(i) = log.current
        {
            *log.passes[i].1.entry(buffer.clone()).or_insert(false) |= written;
        }
    });
}

/// Ends this thread's log: each pass's bytes, in the order the passes were first named.
pub(crate) fn finish() -> Vec<PassTraffic> {
    let log = LOG.with(|l| l.borrow_mut().take()).unwrap_or_default();
    log.passes
        .into_iter()
        .map(|(name, buffers)| {
            let mut t = PassTraffic { name, ..PassTraffic::default() };
            for (buffer, written) in buffers {
                if written {
                    t.written_bytes += buffer.size();
                } else {
                    t.read_bytes += buffer.size();
                }
            }
            t
        })
        .collect()
}
