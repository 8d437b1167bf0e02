// Must not compile when linked to a module below `bus`: fit_message.hpp belongs to bus, whose
// include directory a lower module does not see (tests/CMakeLists.txt, "the module wall").
#include "spindown/fit_message.hpp"
int main() { return 0; }
