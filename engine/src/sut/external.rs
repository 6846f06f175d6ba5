//! Systems under test in another process, over stdin/stdout (SUT_PROTOCOL.md).
//!
//! Every message in either direction is one frame: a 4-byte little-endian length `H`, `H`
//! bytes of a UTF-8 JSON object (the header), then the raw bytes of each binary buffer the
//! header lists under `buffers` (`name`, `dtype`, `shape`, `nbytes`), in that order.

use std::io::{BufReader, Read, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde_json::{json, Value as Json};
use thiserror::Error;

use super::{Sensors, Sut, SutError};
use crate::sensor::Payload;
use crate::{CameraSpec, Control, Observation};

/// The protocol version sent in the `hello` message.
pub const PROTOCOL_VERSION: u32 = 2;
/// The largest header accepted from a system under test, in bytes.
const MAX_HEADER_BYTES: u32 = 1 << 20;

/// How to run an external system under test.
#[derive(Debug, Clone)]
pub struct ExternalConfig {
    /// Program and arguments, e.g. `["python3", "controller.py"]`.
    pub command: Vec<String>,
    /// Longest wait for any answer (handshake, reset, control), seconds, `> 0`.
    pub timeout_s: f64,
    /// Keep processes alive between tests (reset by a `reset` message) instead of starting a
    /// fresh one per test. A process that failed is never reused.
    pub reuse: bool,
    /// Idle processes kept for reuse, shared by the campaign's workers.
    pub pool: Arc<ProcessPool>,
}

/// Why a command cannot be started ([`check_command`]).
#[derive(Debug, Error, Clone, PartialEq, Eq)]
pub enum CommandError {
    /// No program: the command has no words.
    #[error("the command is empty")]
    Empty,
    /// A path (with a `/`) that names no executable file.
    #[error(
        "cannot start `{program}`: no executable file there (relative paths are from the \
         current folder)"
    )]
    NotExecutable {
        /// The program as given.
        program: String,
    },
    /// A bare name that is no executable file in a folder of `PATH`.
    #[error("cannot start `{program}`: no executable of that name in a folder of PATH")]
    NotOnPath {
        /// The program as given.
        program: String,
    },
}

/// How an external system under test broke the protocol or failed: [`SutError::Failed`]'s
/// message after the command.
#[derive(Debug, Error, Clone, PartialEq)]
enum Broke {
    /// Its command cannot be started.
    #[error(transparent)]
    Command(#[from] CommandError),
    /// Its output ended.
    #[error("closed its output")]
    Closed,
    /// A frame it sent cannot be read: malformed, truncated, too large, or its output failed.
    #[error("{0}")]
    Frame(String),
    /// Its hello asked for what cannot be honoured.
    #[error("{0}")]
    Hello(String),
    /// Its hello's `control_hz` is no whole number of physics steps per decision.
    #[error(transparent)]
    Rate(#[from] crate::RateError),
    /// Its process failed: it could not start, died, stopped reading, or did not answer in
    /// time (the message carries the end of its stderr).
    #[error("{0}")]
    Process(String),
    /// An answer that is no control: a value missing, not a number, or outside `[-1, 1]`.
    #[error("{0}")]
    Answer(String),
}

/// Checks that `command`'s program can be started: a path (with a `/`) names an executable
/// file, a bare name is an executable file in a folder of `PATH`. Nothing is run.
///
/// # Errors
/// [`CommandError`]: "the command is empty", or "cannot start `P`: ..." naming what is
/// missing.
pub fn check_command(command: &[String]) -> Result<(), CommandError> {
    let program = command.first().ok_or(CommandError::Empty)?;
    let executable = |p: &std::path::Path| {
        use std::os::unix::fs::PermissionsExt;
        std::fs::metadata(p).is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o111 != 0)
    };
    if program.contains('/') {
        if executable(std::path::Path::new(program)) {
            return Ok(());
        }
        return Err(CommandError::NotExecutable {
            program: program.clone(),
        });
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    if std::env::split_paths(&path).any(|dir| executable(&dir.join(program))) {
        return Ok(());
    }
    Err(CommandError::NotOnPath {
        program: program.clone(),
    })
}

/// A command to start and where to send the started child.
type SpawnRequest = (Command, mpsc::Sender<std::io::Result<Child>>);

/// Starts `command` so that the process dies with paracosm, however paracosm dies (`kill -9`
/// included): the child asks the kernel for `SIGKILL` when its parent goes
/// (`PR_SET_PDEATHSIG`, Linux). The kernel sends it when the *thread* that started the child
/// ends, and the external processes are shared between the worker threads (a pool), so every
/// one is started by a single thread that lives as long as paracosm. Whatever the program
/// starts in turn (a wrapper's child) is not covered: a wrapper should `exec` its program.
///
/// # Errors
/// The I/O error of the start (no such program, no permission).
fn spawn_dying_with_us(mut command: Command) -> std::io::Result<Child> {
    use std::os::unix::process::CommandExt;
    use std::sync::OnceLock;
    static SPAWNER: OnceLock<Mutex<mpsc::Sender<SpawnRequest>>> = OnceLock::new();
    let parent = std::process::id() as libc::pid_t;
    // SAFETY: the closure runs in the child between fork and exec and calls only prctl(2)
    // and getppid(2), which are async-signal-safe; it allocates nothing.
    unsafe {
        command.pre_exec(move || {
            if libc::prctl(
                libc::PR_SET_PDEATHSIG,
                libc::SIGKILL as libc::c_ulong,
                0,
                0,
                0,
            ) == -1
            {
                return Err(std::io::Error::last_os_error());
            }
            // The parent may have died before the request: then no signal would come.
            if libc::getppid() != parent {
                return Err(std::io::Error::from_raw_os_error(libc::ESRCH));
            }
            Ok(())
        });
    }
    let spawner = SPAWNER.get_or_init(|| {
        let (tx, rx) = mpsc::channel::<SpawnRequest>();
        std::thread::Builder::new()
            .name("paracosm-sut-spawner".into())
            .spawn(move || {
                // Never returns while paracosm runs: the sender lives in the static.
                for (mut command, reply) in rx {
                    // Registered under the lock the orphan scan takes: a child just started
                    // is never taken for an orphan.
                    let mut spawned = spawned_children();
                    let child = command.spawn();
                    if let Ok(c) = &child {
                        spawned.insert(c.id());
                    }
                    drop(spawned);
                    let _ = reply.send(child);
                }
            })
            .expect("a thread to start the systems under test");
        Mutex::new(tx)
    });
    let (reply, started) = mpsc::channel();
    spawner
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .send((command, reply))
        .map_err(|_| std::io::Error::other("the spawner thread is gone"))?;
    started
        .recv()
        .map_err(|_| std::io::Error::other("the spawner thread is gone"))?
}

/// Whether this process adopts and kills what its systems under test leave behind
/// ([`track_orphans`]).
static TRACKING_ORPHANS: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// The pids of the systems under test this process started and has not yet waited for.
fn spawned_children() -> std::sync::MutexGuard<'static, std::collections::BTreeSet<u32>> {
    static SPAWNED: Mutex<std::collections::BTreeSet<u32>> =
        Mutex::new(std::collections::BTreeSet::new());
    SPAWNED.lock().unwrap_or_else(|p| p.into_inner())
}

/// Makes this process the reaper of whatever its systems under test start and leave
/// (`PR_SET_CHILD_SUBREAPER`, Linux): a helper that double-forks or calls `setsid` leaves the
/// program's process group, so killing the group misses it; as an orphan it is adopted by this
/// process instead of init, and [`reap_orphans`] kills it when its system under test is done.
/// For the command-line tools, which start nothing else: in a host process (Python) the
/// orphans of unrelated children would be adopted too, so the package does not call it.
///
/// # Errors
/// The error of `prctl(2)`.
pub fn track_orphans() -> std::io::Result<()> {
    // SAFETY: prctl(2) with PR_SET_CHILD_SUBREAPER reads only its integer arguments.
    if unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) } == -1 {
        return Err(std::io::Error::last_os_error());
    }
    TRACKING_ORPHANS.store(true, std::sync::atomic::Ordering::SeqCst);
    Ok(())
}

/// The parent pid of process `pid`, from `/proc/PID/stat` (the field after the command
/// name, which is in parentheses and may hold spaces).
fn parent_of(pid: u32) -> Option<u32> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let after = &stat[stat.rfind(')')? + 1..];
    after.split_whitespace().nth(1)?.parse().ok()
}

/// Kills and waits for every process this one adopted ([`track_orphans`]): its children that
/// it did not start itself. Returns how many. Does nothing unless tracking.
pub fn reap_orphans() -> usize {
    if !TRACKING_ORPHANS.load(std::sync::atomic::Ordering::SeqCst) {
        return 0;
    }
    let me = std::process::id();
    let spawned = spawned_children();
    let Ok(entries) = std::fs::read_dir("/proc") else {
        return 0;
    };
    let mut reaped = 0;
    for e in entries.flatten() {
        let Some(pid) = e.file_name().to_str().and_then(|n| n.parse::<u32>().ok()) else {
            continue;
        };
        if spawned.contains(&pid) || parent_of(pid) != Some(me) {
            continue;
        }
        let Ok(p) = libc::pid_t::try_from(pid) else {
            continue;
        };
        // SAFETY: kill(2) and waitpid(2) on a child of this process; no memory is shared
        // but the status integer.
        unsafe {
            libc::kill(p, libc::SIGKILL);
            let mut status = 0;
            libc::waitpid(p, &mut status, 0);
        }
        reaped += 1;
    }
    reaped
}

/// Kills every process of the process group `pgid` (the system under test and what it
/// started); a group already gone is not an error.
fn kill_group(pgid: u32) {
    if let Ok(pgid) = libc::pid_t::try_from(pgid) {
        if pgid > 0 {
            // SAFETY: kill(2) with a negative pid signals that process group; no memory is
            // touched.
            unsafe {
                libc::kill(-pgid, libc::SIGKILL);
            }
        }
    }
}

impl ExternalConfig {
    /// A configuration with a fresh, empty pool.
    pub fn new(command: Vec<String>, timeout_s: f64, reuse: bool) -> Self {
        ExternalConfig {
            command,
            timeout_s,
            reuse,
            pool: Arc::new(ProcessPool::default()),
        }
    }
}

impl PartialEq for ExternalConfig {
    fn eq(&self, other: &Self) -> bool {
        self.command == other.command
            && self.timeout_s == other.timeout_s
            && self.reuse == other.reuse
    }
}

/// Idle external processes, handed to the next test that needs one (at most one per worker is
/// ever alive at a time).
#[derive(Debug, Default)]
pub struct ProcessPool {
    idle: Mutex<Vec<Process>>,
}

/// A message from the system under test: its JSON header (any buffers it sent are read and
/// dropped, to stay in step).
#[derive(Debug)]
struct Message {
    header: Json,
}

/// A running system-under-test process.
#[derive(Debug)]
struct Process {
    child: Child,
    /// `None` once closed (when the process is dropped).
    stdin: Option<ChildStdin>,
    replies: Receiver<Result<Message, Broke>>,
    stderr: Arc<Mutex<String>>,
    sensors: Sensors,
    wants_depth: bool,
    /// The sensors the program asked for by name with `true` in its hello (`lidar`...).
    wanted: Vec<String>,
    /// Dropped after [`Process`]'s own drop: kills the program's process group.
    _group: GroupGuard,
}

impl Drop for Process {
    fn drop(&mut self) {
        // Closing stdin asks the program to exit; give it 100 ms, then kill it.
        self.stdin = None;
        for _ in 0..10 {
            if let Ok(Some(_)) = self.child.try_wait() {
                self.forget();
                return;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.forget();
    }
}

impl Process {
    /// Forgets the child's pid once it has been waited for (it may be reused).
    fn forget(&self) {
        spawned_children().remove(&self.child.id());
    }
}

impl Drop for GroupGuard {
    fn drop(&mut self) {
        // Whatever the program started (a wrapper script's child, a helper) is in its group:
        // none of it outlives the test. What left the group (`setsid`, a double fork) was
        // adopted by paracosm when its parent died, and is killed now.
        kill_group(self.0);
        reap_orphans();
    }
}

/// Kills the system under test's process group when dropped (after [`Process`]'s own drop
/// has let the program exit).
#[derive(Debug)]
struct GroupGuard(u32);

fn read_message(r: &mut impl Read) -> Result<Option<Message>, Broke> {
    let mut len = [0u8; 4];
    match r.read_exact(&mut len) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
        Err(e) => return Err(Broke::Frame(format!("cannot read its output: {e}"))),
    }
    let len = u32::from_le_bytes(len);
    if len > MAX_HEADER_BYTES {
        return Err(Broke::Frame(format!(
            "sent a malformed frame: header length {len} bytes is over the {MAX_HEADER_BYTES}-byte \
             limit (bytes {:02x?}; is it printing to stdout?)",
            len.to_le_bytes()
        )));
    }
    let mut header = vec![0u8; len as usize];
    r.read_exact(&mut header)
        .map_err(|e| Broke::Frame(format!("sent a truncated frame: {e}")))?;
    let header: Json = serde_json::from_slice(&header).map_err(|e| {
        let text = String::from_utf8_lossy(&header[..header.len().min(80)]);
        let hint = if text.contains("NaN") || text.contains("Infinity") {
            " (NaN and Infinity are not JSON numbers: controls must be finite, in [-1, 1])"
        } else {
            ""
        };
        Broke::Frame(format!(
            "sent a malformed frame: the header is not JSON ({e}){hint}: {text:?}"
        ))
    })?;
    if let Some(list) = header.get("buffers").and_then(Json::as_array) {
        for b in list {
            let n = b.get("nbytes").and_then(Json::as_u64).ok_or_else(|| {
                Broke::Frame("sent a malformed frame: a buffer has no `nbytes`".into())
            })?;
            if n > 1 << 30 {
                return Err(Broke::Frame(format!(
                    "sent a malformed frame: buffer of {n} bytes"
                )));
            }
            let mut data = vec![0u8; n as usize];
            r.read_exact(&mut data)
                .map_err(|e| Broke::Frame(format!("sent a truncated buffer: {e}")))?;
        }
    }
    Ok(Some(Message { header }))
}

fn write_message(w: &mut impl Write, header: &Json, buffers: &[&[u8]]) -> std::io::Result<()> {
    let text = serde_json::to_vec(header).expect("JSON values serialise");
    w.write_all(&(text.len() as u32).to_le_bytes())?;
    w.write_all(&text)?;
    for b in buffers {
        w.write_all(b)?;
    }
    w.flush()
}

impl Process {
    fn spawn(config: &ExternalConfig, dt_s: f64) -> Result<Process, Broke> {
        let (program, args) = config.command.split_first().ok_or(CommandError::Empty)?;
        use std::os::unix::process::CommandExt;
        // Its own process group, so that it and everything it starts can be killed at once.
        let mut command = Command::new(program);
        command
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .process_group(0);
        let mut child = spawn_dying_with_us(command)
            .map_err(|e| Broke::Process(format!("cannot start `{program}`: {e}")))?;
        let stdin = child.stdin.take().expect("piped");
        let stdout = child.stdout.take().expect("piped");
        let mut err_pipe = child.stderr.take().expect("piped");
        let (tx, replies) = mpsc::channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(stdout);
            loop {
                let m = read_message(&mut r);
                let stop = !matches!(m, Ok(Some(_)));
                let m = m.and_then(|m| m.ok_or(Broke::Closed));
                if tx.send(m).is_err() || stop {
                    break;
                }
            }
        });
        let stderr = Arc::new(Mutex::new(String::new()));
        let tail = Arc::clone(&stderr);
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = err_pipe.read(&mut buf) {
                if n == 0 {
                    break;
                }
                let mut t = tail.lock().unwrap_or_else(|p| p.into_inner());
                t.push_str(&String::from_utf8_lossy(&buf[..n]));
                // Keep the last 4 KiB: where the traceback is.
                if t.len() > 8192 {
                    let cut = t.len() - 4096;
                    let cut = (cut..t.len()).find(|&i| t.is_char_boundary(i)).unwrap_or(0);
                    t.drain(..cut);
                }
            }
        });
        let group = GroupGuard(child.id());
        let mut p = Process {
            child,
            _group: group,
            stdin: Some(stdin),
            replies,
            stderr,
            sensors: Sensors::default(),
            wants_depth: false,
            wanted: Vec::new(),
        };
        let hello = p.request(
            &json!({"type": "hello", "protocol": PROTOCOL_VERSION, "dt_s": dt_s}),
            &[],
            config.timeout_s,
        )?;
        p.accept_hello(&hello.header)?;
        Ok(p)
    }

    fn accept_hello(&mut self, h: &Json) -> Result<(), Broke> {
        if h.get("type").and_then(Json::as_str) != Some("hello") {
            return Err(Broke::Hello(format!(
                "answered the hello with {h} instead of a hello"
            )));
        }
        let sensors = h.get("sensors").cloned().unwrap_or(Json::Null);
        match &sensors {
            Json::Null => {}
            Json::Object(m) => {
                // `"lidar": "yes"` sent nothing and said nothing: every sensor but the camera
                // (which may be an object) is asked for with true or false.
                for (name, v) in m {
                    if name != "camera" && !v.is_boolean() {
                        return Err(Broke::Hello(format!(
                            "declared sensor `{name}` as {v}; a sensor is asked for with true \
                             or false (the camera also with an object)"
                        )));
                    }
                }
            }
            other => {
                return Err(Broke::Hello(format!(
                    "declared sensors {other}; need an object such as {{\"lidar\": true}}"
                )))
            }
        }
        self.wants_depth = sensors
            .get("depth")
            .and_then(Json::as_bool)
            .unwrap_or(false);
        self.wanted = sensors
            .as_object()
            .map(|m| {
                m.iter()
                    .filter(|(_, v)| v.as_bool() == Some(true))
                    .map(|(k, _)| k.clone())
                    .collect()
            })
            .unwrap_or_default();
        let camera = match sensors.get("camera") {
            None | Some(Json::Null) | Some(Json::Bool(false)) => None,
            Some(Json::Bool(true)) => Some(CameraSpec::default()),
            Some(spec) => {
                let c: CameraSpec = serde_json::from_value(spec.clone())
                    .map_err(|e| Broke::Hello(format!("declared an invalid camera {spec}: {e}")))?;
                c.validate()
                    .map_err(|e| Broke::Hello(format!("declared an invalid camera: {e}")))?;
                Some(c)
            }
        };
        let camera = match (camera, self.wants_depth) {
            (None, true) => Some(CameraSpec::default()),
            (c, _) => c,
        };
        let control_hz = match h.get("control_hz") {
            None | Some(Json::Null) => None,
            Some(v) => match v.as_f64() {
                Some(hz) if hz.is_finite() && hz > 0.0 => {
                    crate::steps_per_period("declared control_hz", hz, crate::DEFAULT_DT_S)?;
                    Some(hz)
                }
                _ => {
                    return Err(Broke::Hello(format!(
                        "declared control_hz {v}; need a positive number"
                    )))
                }
            },
        };
        self.sensors = Sensors {
            camera,
            control_hz,
            // The protocol sends the image, and the depth map when asked; never the labels.
            frame_use: crate::FrameUse {
                depth: self.wants_depth,
                labels: false,
                region: None,
            },
        };
        Ok(())
    }

    /// The arrays of every reading in `obs` this program declared (SUT_PROTOCOL.md), in the
    /// order of the sensors' names.
    ///
    /// # Errors
    /// [`Broke::Hello`] for a sensor it asked for by a name the simulation does not mount
    /// (`"lidr": true`), naming the ones it mounts, rather than sending nothing.
    fn declared_readings(&self, obs: &Observation<'_>) -> Result<Vec<Payload>, Broke> {
        // A sensor asked for by a name the simulation does not mount (`"lidr": true`) ends
        // the test, naming the ones it mounts, rather than sending nothing.
        if let Some(unknown) = self.wanted.iter().find(|w| {
            !matches!(w.as_str(), "camera" | "depth") && !obs.readings.iter().any(|(n, _)| n == w)
        }) {
            let mut mounted: Vec<&str> = obs.readings.iter().map(|(n, _)| *n).collect();
            mounted.extend(["camera", "depth"]);
            mounted.sort_unstable();
            mounted.dedup();
            let message = format!(
                "declared sensor `{unknown}`, which the simulation does not mount (it mounts: {})",
                mounted.join(", ")
            );
            return Err(Broke::Hello(message));
        }
        let mut readings: Vec<_> = obs.readings.iter().collect();
        readings.sort_by_key(|(name, _)| *name);
        let mut sent = Vec::new();
        for (name, reading) in readings {
            let wanted = match *name {
                "camera" => self.sensors.camera.is_some(),
                other => self.wanted.iter().any(|w| w == other),
            };
            if wanted {
                sent.extend(reading.payloads(self.wants_depth));
            }
        }
        Ok(sent)
    }

    /// Sends one message and waits for the answer.
    fn request(
        &mut self,
        header: &Json,
        buffers: &[&[u8]],
        timeout_s: f64,
    ) -> Result<Message, Broke> {
        let written = match self.stdin.as_mut() {
            Some(stdin) => write_message(stdin, header, buffers),
            None => Err(std::io::Error::other("stdin closed")),
        };
        if let Err(e) = written {
            return Err(self.died(&format!("stopped reading its input ({e})")));
        }
        match self
            .replies
            .recv_timeout(Duration::from_secs_f64(timeout_s))
        {
            Ok(Ok(m)) => Ok(m),
            Ok(Err(e)) => Err(self.died(&e.to_string())),
            Err(RecvTimeoutError::Timeout) => {
                kill_group(self.child.id());
                Err(Broke::Process(format!(
                    "did not answer within {timeout_s} s (--sut-timeout); killed it{}",
                    self.stderr_tail()
                )))
            }
            Err(RecvTimeoutError::Disconnected) => Err(self.died("closed its output")),
        }
    }

    /// How the process ended, after `what` went wrong: its exit status and the end of its
    /// stderr.
    fn died(&mut self, what: &str) -> Broke {
        // Give a crashing process a moment to finish writing its traceback and exit.
        let mut status = None;
        for _ in 0..50 {
            if let Ok(Some(s)) = self.child.try_wait() {
                status = Some(s);
                break;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
        std::thread::sleep(Duration::from_millis(20));
        let status = status.map_or_else(
            || "the process was still running (killed)".to_string(),
            |s| format!("process {s}"),
        );
        Broke::Process(format!("{what}; {status}{}", self.stderr_tail()))
    }

    fn stderr_tail(&self) -> String {
        let t = self.stderr.lock().unwrap_or_else(|p| p.into_inner());
        let lines: Vec<&str> = t.trim_end().lines().collect();
        if lines.is_empty() {
            String::new()
        } else {
            let from = lines.len().saturating_sub(5);
            format!("; its stderr ends with: {}", lines[from..].join(" | "))
        }
    }
}

/// A system under test in another process, speaking the protocol of SUT_PROTOCOL.md over its
/// stdin and stdout. Any failure of the process (it crashes, hangs past the timeout, writes
/// garbage, answers NaN or controls outside `[-1, 1]`) becomes a [`SutError`]: the test is
/// recorded as an `error` and the process is killed, never reused.
#[derive(Debug)]
pub struct ExternalSut {
    config: ExternalConfig,
    process: Option<Process>,
    healthy: bool,
    /// The number of the next observation in this test, from 0: sent as `step`, and the
    /// answer must carry it back (SUT_PROTOCOL.md).
    step: u64,
    /// The route last sent (its address and length in the observation), so that a route is
    /// sent in the first observation that has one and again only when it changes.
    route_sent: (usize, usize),
}

impl ExternalSut {
    /// A system that will start (or take from the pool) its process at the first reset.
    pub fn new(config: ExternalConfig) -> Self {
        ExternalSut {
            config,
            process: None,
            healthy: false,
            step: 0,
            route_sent: (0, 0),
        }
    }

    fn fail(&mut self, message: impl std::fmt::Display) -> SutError {
        self.healthy = false;
        self.process = None; // kills it
        SutError::Failed(format!(
            "external system under test `{}` {message}",
            self.config.command.join(" ")
        ))
    }
}

impl Drop for ExternalSut {
    fn drop(&mut self) {
        if let (true, true, Some(p)) = (self.config.reuse, self.healthy, self.process.take()) {
            self.config
                .pool
                .idle
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push(p);
        }
    }
}

impl Sut for ExternalSut {
    fn sensors(&self) -> Sensors {
        self.process
            .as_ref()
            .map(|p| p.sensors.clone())
            .unwrap_or_default()
    }

    fn reset(&mut self, seed: u64) -> Result<(), SutError> {
        // The physics step is not known here; the hello carries the default step.
        let dt_s = crate::DEFAULT_DT_S;
        self.step = 0;
        self.route_sent = (0, 0);
        if self.process.is_none() {
            let pooled = if self.config.reuse {
                self.config
                    .pool
                    .idle
                    .lock()
                    .unwrap_or_else(|p| p.into_inner())
                    .pop()
            } else {
                None
            };
            self.process = Some(match pooled {
                Some(p) => p,
                None => Process::spawn(&self.config, dt_s).map_err(|e| self.fail(e))?,
            });
        }
        let timeout = self.config.timeout_s;
        let p = self.process.as_mut().expect("set above");
        let reply = p.request(&json!({"type": "reset", "seed": seed}), &[], timeout);
        match reply {
            Ok(m) if m.header.get("type").and_then(Json::as_str) == Some("ready") => {
                self.healthy = true;
                Ok(())
            }
            Ok(m) => Err(self.fail(format!(
                "answered the reset with {} instead of {{\"type\": \"ready\"}}",
                m.header
            ))),
            Err(e) => Err(self.fail(e)),
        }
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let timeout = self.config.timeout_s;
        let Some(p) = self.process.as_mut() else {
            return Err(self.fail("was not started (no reset)"));
        };
        let step = self.step;
        self.step += 1;
        let mut header = observation_header(obs, step, &mut self.route_sent);
        // Every reading the program declared, as named arrays (SUT_PROTOCOL.md), in the
        // order of their names.
        let sent = match p.declared_readings(obs) {
            Ok(sent) => sent,
            Err(e) => return Err(self.fail(e)),
        };
        let descriptors = buffer_descriptors(&sent);
        let payloads: Vec<&[u8]> = sent.iter().map(|b| b.bytes.as_slice()).collect();
        header["buffers"] = Json::Array(descriptors);
        let reply = match p.request(&header, &payloads, timeout) {
            Ok(m) => m,
            Err(e) => return Err(self.fail(e)),
        };
        // An answer that runs behind (a second answer to an earlier observation) or ahead is
        // an error of this test, never a control applied at the wrong step.
        if let Some(message) = wrong_step(&reply.header, step) {
            return Err(self.fail(message));
        }
        match (
            control_value(&reply.header, "throttle"),
            control_value(&reply.header, "steering"),
        ) {
            (Ok(throttle), Ok(steering)) => Ok(Control { throttle, steering }),
            (Err(e), _) | (_, Err(e)) => Err(self.fail(e)),
        }
    }
}

/// The header of observation number `step`, without its `buffers`: time (s), the ego's
/// position (m), heading (rad), speed (m/s) and set speed (m/s) when the scenario asks one,
/// and the route (m) when it is the first one or differs from `route_sent` (its address and
/// length), which it then records.
fn observation_header(obs: &Observation<'_>, step: u64, route_sent: &mut (usize, usize)) -> Json {
    let mut header = json!({
        "type": "observation",
        "step": step,
        "t_s": obs.t_s,
        "ego": {
            "pos_m": obs.ego.pos_m,
            "heading_rad": obs.ego.heading_rad,
            "speed_mps": obs.ego.speed_mps,
        },
    });
    // The speed the scenario asks the ego to keep (an OpenSCENARIO `Init` speed), when it
    // asks one.
    if let Some(v) = obs.set_speed_mps {
        header["ego"]["set_speed_mps"] = json!(v);
    }
    // The route to follow, in the first observation that has one and when it changes (a
    // storyboard's lane change or route of the ego).
    let route = (obs.route.as_ptr() as usize, obs.route.len());
    if !obs.route.is_empty() && route != *route_sent {
        header["route_m"] = json!(obs.route);
        *route_sent = route;
    }
    header
}

/// The `buffers` descriptors of the arrays `sent` (SUT_PROTOCOL.md): name, dtype, shape,
/// byte count and, where the reading has one, its time (s).
fn buffer_descriptors(sent: &[Payload]) -> Vec<Json> {
    sent.iter()
        .map(|b| {
            let mut d = json!({"name": b.name, "dtype": b.dtype, "shape": b.shape,
                "nbytes": b.bytes.len()});
            if let Some(t) = b.t_s {
                d["t_s"] = json!(t);
            }
            d
        })
        .collect()
}

/// What is wrong with an answer that does not carry the `step` of the observation it
/// answers (the failure's message); `None` when it carries it.
fn wrong_step(header: &Json, step: u64) -> Option<String> {
    match header.get("step").map(Json::as_u64) {
        Some(Some(s)) if s == step => None,
        Some(Some(s)) => Some(format!(
            "answered step {s} to the observation of step {step}: {} (each \
             observation gets exactly one answer, which carries its `step`)",
            if s < step {
                "an extra or late answer"
            } else {
                "an answer ahead of its observation"
            }
        )),
        Some(None) => Some(format!(
            "answered `step` = {}; it must be the observation's step, a whole number",
            header["step"]
        )),
        None => Some(format!(
            "answered {header} without `step` (protocol {PROTOCOL_VERSION}: the answer \
             carries the observation's step)"
        )),
    }
}

/// The control `k` of an answer: a finite number in `[-1, 1]`.
fn control_value(header: &Json, k: &str) -> Result<f64, Broke> {
    let v = header
        .get(k)
        .ok_or_else(|| Broke::Answer(format!("answered {header} without `{k}`")))?;
    // JSON has no NaN: clients that write `NaN` send a string or a bare token the
    // parser rejects; both end here or in the frame reader.
    let x = v
        .as_f64()
        .ok_or_else(|| Broke::Answer(format!("answered {k} = {v}; controls must be numbers")))?;
    if !x.is_finite() || !(-1.0..=1.0).contains(&x) {
        return Err(Broke::Answer(format!(
            "answered {k} = {x}, outside [-1, 1]"
        )));
    }
    Ok(x)
}
