// Must not link in the physics: LCM's header is a system header any file can name, but the
// library itself is linked only from bus up, so a call into it is an undefined reference.
#include <lcm/lcm.h>
int main() {
  lcm_t* lcm = lcm_create("memq://");
  if (lcm) lcm_destroy(lcm);
  return 0;
}
