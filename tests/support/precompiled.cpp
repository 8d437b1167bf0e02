// The translation unit that precompiles the unit tests' common headers (tests/CMakeLists.txt,
// SPINDOWN_PRECOMPILED_HEADERS): every unit test reuses its precompiled header.
