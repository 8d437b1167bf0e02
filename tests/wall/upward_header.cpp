// Must not compile when linked to the physics, to bus or to logio: fit_message.hpp belongs to
// wire, where transport and physics meet, whose include directory they do not see
// (tests/CMakeLists.txt, "the module wall").
#include "spindown/fit_message.hpp"
int main() { return 0; }
