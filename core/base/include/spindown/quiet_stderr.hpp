#pragma once
// Holds back what a library prints on stderr (fd 2 goes to /dev/null) while it lives, or until
// restore(). LCM 1.3.1 prints its own advice when multicast does not work ("LCM self test
// failed!!", a route hint); the doctor says it with the fix instead.
namespace spindown {

class QuietStderr {
 public:
  QuietStderr();
  ~QuietStderr() { restore(); }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;
  void restore();  // stderr is back; idempotent

 private:
  int saved_ = -1;
};

}  // namespace spindown
