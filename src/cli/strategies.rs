//! `dibench strategies`: the catalogue, and which strategies apply to a scene.

use crate::error::Result;
use crate::strategy::{self, Strategy};
use clap::Args;

#[derive(Args, Debug)]
pub struct StrategiesArgs {
    /// Scene file or name under scenes/.
    pub scene: Option<String>,
}

pub fn run(a: StrategiesArgs, strategies: &[Box<dyn Strategy>]) -> Result<()> {
    let prepared = a.scene.as_deref().map(super::load).transpose()?;
    for s in strategies {
        let status = match &prepared {
            None => String::new(),
            Some(p) => match strategy::applies(s.as_ref(), p) {
                Ok(()) => "  [applies]".into(),
                Err(why) => format!("  [skipped: {why}]"),
            },
        };
        println!("{:<20} {}{status}", s.name(), s.describe());
    }
    Ok(())
}
