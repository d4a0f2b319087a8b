# Sourced by the experiment scripts (from the repository's root): the contactlab binary they
# run, in `bin`. CONTACTLAB_BIN set: that binary (an older build for a before/after, say);
# unset: target/release/contactlab, built first, with CMake for the OSQP backend
# (scripts/ensure-cmake.sh).
if [ -z "${CONTACTLAB_BIN:-}" ]; then
  source scripts/ensure-cmake.sh
  cargo build --release --quiet --bin contactlab
fi
bin=${CONTACTLAB_BIN:-target/release/contactlab}
