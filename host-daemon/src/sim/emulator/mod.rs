//! Device emulators that speak the stage's and servo's serial protocols byte for byte, each
//! on its own thread at the far end of a port (in tests, the master side of a real
//! pseudo-terminal from [`serialport::TTYPort::pair`], the driver holding the slave side).
//! They record every byte received, so tests can check what was sent, and can be told to
//! misbehave.

mod maestro;
mod vxm;

pub use maestro::{MaestroEmulator, MaestroFault};
pub use vxm::{DEFAULT_LIMIT_BELOW_STEPS, VxmEmulator, VxmFault};

use serialport::SerialPort;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::Duration;

/// A device model the runner feeds and ticks.
trait Device: Send + 'static {
    /// Bytes arrived from the host; answers go to `out`.
    fn feed(&mut self, bytes: &[u8], out: &mut Vec<u8>);
    /// Time passes (real time, read by the model itself); spontaneous output goes to `out`.
    fn tick(&mut self, out: &mut Vec<u8>);
}

/// One emulator thread and the model it shares with the test.
#[derive(Debug)]
struct Runner<D> {
    model: Arc<Mutex<D>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl<D: Device> Runner<D> {
    fn spawn<P: SerialPort + 'static>(mut port: P, model: D) -> Self {
        let model = Arc::new(Mutex::new(model));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let model = Arc::clone(&model);
            let stop = Arc::clone(&stop);
            std::thread::spawn(move || {
                // A failure to set the timeout leaves the default (100 ms): slower, not wrong.
                let _ = port.set_timeout(Duration::from_millis(2));
                let mut buffer = [0u8; 256];
                let mut out = Vec::new();
                while !stop.load(Ordering::Relaxed) {
                    match port.read(&mut buffer) {
                        Ok(n) if n > 0 => lock(&model).feed(&buffer[..n], &mut out),
                        Ok(_) => {}
                        Err(error) if error.kind() == std::io::ErrorKind::TimedOut => {}
                        // No slave open, or a transient error: wait and carry on.
                        Err(_) => std::thread::sleep(Duration::from_millis(2)),
                    }
                    lock(&model).tick(&mut out);
                    if !out.is_empty() {
                        // A host that has gone away loses the answer, as on a real wire.
                        let _ = port.write_all(&out);
                        out.clear();
                    }
                }
            })
        };
        Self {
            model,
            stop,
            thread: Some(thread),
        }
    }

    fn model(&self) -> MutexGuard<'_, D> {
        lock(&self.model)
    }

    /// Stops the thread, which closes its end of the port.
    fn close(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            // A panicked emulator thread has nothing more to report.
            let _ = thread.join();
        }
    }
}

impl<D> Drop for Runner<D> {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

fn lock<D>(model: &Mutex<D>) -> MutexGuard<'_, D> {
    model.lock().unwrap_or_else(PoisonError::into_inner)
}
