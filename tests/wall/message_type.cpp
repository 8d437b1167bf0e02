// Must not compile in the physics: the lcm-gen message types are bus's and what links it.
#include "spindown/fit_t.hpp"
int main() { return sizeof(spindown::fit_t) == 0; }
