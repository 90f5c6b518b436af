//! A `tracer` child process watched from the test: its standard error read
//! line by line as it comes (to act when a line appears), signals sent to
//! it, and a time limit after which it is killed, so that a regression
//! that hangs fails the test instead of stalling the suite.

use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};
use std::sync::mpsc::{channel, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// A running child.
pub struct Watched {
    pid: libc::pid_t,
    start: Instant,
    lines: Receiver<String>,
    stderr: Arc<Mutex<String>>,
    stdout: Option<JoinHandle<Vec<u8>>>,
    reaped: bool,
}

/// How a watched child ended.
#[derive(Debug)]
pub struct Finished {
    /// Its exit status, when it exited (not killed by a signal).
    pub code: Option<i32>,
    /// The signal that killed it, if one did.
    pub signal: Option<i32>,
    /// Whether the test killed it for running past its limit.
    pub timed_out: bool,
    /// From the spawn to its end.
    pub elapsed: Duration,
    pub stdout: String,
    pub stderr: String,
}

impl Watched {
    /// Starts `command` with its output piped to the test and no input.
    pub fn spawn(command: &mut Command) -> Watched {
        command
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let start = Instant::now();
        let mut child = command.spawn().expect("the child starts");
        let pid = child.id() as libc::pid_t;
        let mut stdout = child.stdout.take().unwrap();
        let stderr = child.stderr.take().unwrap();
        // The `Child` is dropped without waiting: `finish` reaps it by its
        // pid, so that it can poll with a deadline.
        drop(child);
        let stdout = std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = stdout.read_to_end(&mut bytes);
            bytes
        });
        let (send, lines) = channel();
        let all = Arc::new(Mutex::new(String::new()));
        let all_writer = all.clone();
        std::thread::spawn(move || {
            let mut reader = BufReader::new(stderr);
            let mut line = Vec::new();
            while reader.read_until(b'\n', &mut line).is_ok_and(|n| n > 0) {
                let text = String::from_utf8_lossy(&line).into_owned();
                all_writer.lock().unwrap().push_str(&text);
                let _ = send.send(text);
                line.clear();
            }
        });
        Watched {
            pid,
            start,
            lines,
            stderr: all,
            stdout: Some(stdout),
            reaped: false,
        }
    }

    /// Waits (at most `limit`) for a line of standard error containing
    /// `needle`; false if none came, or the child closed its standard error.
    pub fn wait_for_line(&self, needle: &str, limit: Duration) -> bool {
        let deadline = Instant::now() + limit;
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.lines.recv_timeout(left) {
                Ok(line) if line.contains(needle) => return true,
                Ok(_) => {}
                Err(RecvTimeoutError::Timeout | RecvTimeoutError::Disconnected) => return false,
            }
        }
    }

    /// Standard error so far.
    pub fn stderr_so_far(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    /// The child's process id.
    pub fn pid(&self) -> u32 {
        self.pid as u32
    }

    /// Sends `signal` to the child (not yet reaped, so the pid is still its own).
    pub fn signal(&self, signal: i32) {
        // SAFETY: kill(2) on our own child, which has not been reaped.
        let r = unsafe { libc::kill(self.pid, signal) };
        assert_eq!(r, 0, "kill({}, {signal}) failed", self.pid);
    }

    /// Waits for the child to end, killing it once `limit` has passed since
    /// it started; returns how it ended.
    pub fn finish(mut self, limit: Duration) -> Finished {
        let mut timed_out = false;
        let status = loop {
            let mut status = 0;
            // SAFETY: waitpid on our own child, with a valid out-pointer.
            let r = unsafe { libc::waitpid(self.pid, &mut status, libc::WNOHANG) };
            if r == self.pid {
                break status;
            }
            assert_eq!(r, 0, "waitpid failed: {}", std::io::Error::last_os_error());
            if !timed_out && self.start.elapsed() > limit {
                timed_out = true;
                // SAFETY: kill(2) on our own child, not yet reaped.
                unsafe { libc::kill(self.pid, libc::SIGKILL) };
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        self.reaped = true;
        let elapsed = self.start.elapsed();
        let stdout = self.stdout.take().unwrap().join().unwrap();
        // The reader ends when the child's end of the pipe closes.
        while self.lines.recv_timeout(Duration::from_secs(5)).is_ok() {}
        let (exited, signaled) = (libc::WIFEXITED(status), libc::WIFSIGNALED(status));
        Finished {
            code: exited.then(|| libc::WEXITSTATUS(status)),
            signal: signaled.then(|| libc::WTERMSIG(status)),
            timed_out,
            elapsed,
            stdout: String::from_utf8_lossy(&stdout).into_owned(),
            stderr: self.stderr_so_far(),
        }
    }
}

impl Drop for Watched {
    /// A test that fails half way leaves no child running.
    fn drop(&mut self) {
        if !self.reaped {
            // SAFETY: kill and waitpid on our own child, not yet reaped.
            unsafe {
                libc::kill(self.pid, libc::SIGKILL);
                libc::waitpid(self.pid, std::ptr::null_mut(), 0);
            }
        }
    }
}

/// Runs `command` to its end, killed after `limit`.
pub fn run_limited(command: &mut Command, limit: Duration) -> Finished {
    Watched::spawn(command).finish(limit)
}
