/// @file default_options.cpp
/// @brief The sanitizers' options, compiled into every executable of a sanitized build (the
///        CLI, the tests, the fuzzers), so that a test, a CLI run inside a test and a fuzzing
///        campaign all run the same way; ASAN_OPTIONS and the like still override them.
///        - A failed allocation throws std::bad_alloc as in a normal build (the budget tests
///          rely on it) instead of stopping the process.
///        - Every report stops the program; leaks are checked at exit.
///        - The suppressions (next to this file) silence findings inside Debian's libraries.

extern "C" {

const char* __asan_default_options() { return "allocator_may_return_null=1:detect_leaks=1"; }

const char* __lsan_default_options()
{
    return "suppressions=" VDB_EWA_SANITIZER_DIR "/lsan.supp:print_suppressions=0";
}

const char* __ubsan_default_options()
{
    return "print_stacktrace=1:halt_on_error=1:suppressions=" VDB_EWA_SANITIZER_DIR "/ubsan.supp";
}

} // extern "C"
