//! The progress bar on stderr: the command line's [`Progress`] observer.
//!
//! One indicatif bar per stage of a library operation; nothing is drawn
//! when stderr is not a terminal.

use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use irsig::progress::{Progress, Stage};

/// A progress bar on stderr, redrawn per stage.
pub(crate) struct Bar {
    shown: bool,
    bar: Mutex<ProgressBar>,
}

impl Bar {
    /// A bar drawn when stderr is a terminal (hidden otherwise).
    pub(crate) fn on_terminal() -> Arc<Bar> {
        Arc::new(Bar {
            shown: std::io::stderr().is_terminal(),
            bar: Mutex::new(ProgressBar::hidden()),
        })
    }

    fn bar(&self) -> ProgressBar {
        // A clone shares the bar's state; a poisoned lock still holds a bar.
        match self.bar.lock() {
            Ok(b) => b.clone(),
            Err(p) => p.into_inner().clone(),
        }
    }
}

impl Progress for Bar {
    fn start(&self, stage: Stage, total: u64) {
        if !self.shown {
            return;
        }
        let bar = ProgressBar::new(total);
        let template = match stage {
            // No count: a turning spinner, what runs and the clock.
            Stage::Load | Stage::Bvh => "{spinner} {msg:28} ({elapsed})".to_string(),
            // The count comes in one step at the end: a spinner, the item
            // and the clock.
            Stage::Thermal => "{spinner} {len} facets: {msg:28} ({elapsed})".to_string(),
            _ => format!(
                "{{spinner}} {{msg:20}} [{{bar:40}}] {{pos}}/{{len}} {} ({{eta}})",
                stage.unit()
            ),
        };
        bar.set_style(
            ProgressStyle::with_template(&template)
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        let message = match stage {
            Stage::Load => Some("loading the scene"),
            Stage::Bvh => Some("building the BVH"),
            Stage::Thermal => Some("thermal passes"),
            _ => None,
        };
        if let Some(m) = message {
            bar.set_message(m);
            bar.enable_steady_tick(Duration::from_millis(100));
        }
        let old = match self.bar.lock() {
            Ok(mut b) => std::mem::replace(&mut *b, bar),
            Err(p) => std::mem::replace(&mut *p.into_inner(), bar),
        };
        old.finish_and_clear();
    }

    fn item(&self, name: &str) {
        self.bar().set_message(name.to_string());
    }

    fn advance(&self, n: u64) {
        self.bar().inc(n);
    }

    fn finish(&self) {
        self.bar().finish_and_clear();
    }
}
