// Must not compile below `bus`: the lcm-gen message types are bus's and above.
#include "spindown/fit_t.hpp"
int main() { return sizeof(spindown::fit_t) == 0; }
