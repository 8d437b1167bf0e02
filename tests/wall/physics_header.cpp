// The transport reaches no physics: the fits' header is out of sight of bus and logio (and of the
// logger that links only them), in sight of fit itself.
#include "spindown/fit.hpp"
int main() { return 0; }
