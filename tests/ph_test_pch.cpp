// The object the tests' precompiled header is made with (tests/CMakeLists.txt, ph_test_pch): nothing of its own.
