//! placeholder for rk45
