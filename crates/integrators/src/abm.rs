//! placeholder for abm
