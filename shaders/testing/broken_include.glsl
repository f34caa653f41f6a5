// Deliberately broken include for native/tests/test_gl.cpp: the error must be
// reported against this file, not the shader that includes it.
// GLINT_TEST_ERROR_NEXT_LINE
float broken_helper() { return undeclared_in_include; }
