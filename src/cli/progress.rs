//! Progress bars on stderr (indicatif) for the library's long steps.

use antiradiance::progress::Progress;

/// One bar at a time, replaced at each step.
#[derive(Default)]
pub struct Bars(std::cell::RefCell<Option<indicatif::ProgressBar>>);

impl Progress for Bars {
    fn begin(&self, step: &str, total: u64) {
        let bar = indicatif::ProgressBar::new(total).with_message(step.to_string());
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg:>12} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        *self.0.borrow_mut() = Some(bar);
    }
    fn advance(&self, n: u64) {
        if let Some(b) = self.0.borrow().as_ref() {
            b.inc(n);
        }
    }
    fn end(&self) {
        if let Some(b) = self.0.borrow_mut().take() {
            b.finish();
        }
    }
}
