//! `bench`: placeholder until the next commit.
use crate::util::Result;
pub fn run() -> Result<()> {
    Err("bench is not implemented yet".into())
}
