#pragma once
// Instances that share one service name on one lab (issue 31): two fitters both started as
// "fitter" publish one heartbeat channel (SPINDOWN.fitter.STATUS) and the same benches' RUN and
// FIT, so their results mix. Their STATUS tells them apart — host, pid, start time and session —
// and ServiceInstances, fed every STATUS heard on one name, names two that are alive at once:
// the fitter itself (its own session counts as alive) and `spindown watch` use it.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/status_t.hpp>

namespace spindown {

struct ServiceInstance {
  std::string host;
  std::int32_t pid = 0;
  std::uint64_t session = 0;
  std::int64_t start_utime = 0;
  std::int64_t last_heard_us = 0;  // receive time of its latest STATUS
  bool own = false;                // this process (always alive)
};

// "host lab-pc pid 4242 session 3f9a0c1d5e7b2a48 started 14:02:07"
std::string instance_text(const ServiceInstance& i);

class ServiceInstances {
 public:
  // service, instance: the name watched ("fitter", "fitter"); alive_s: an instance not heard for
  // this long is gone (a stopped or restarted one); max_instances bounds the list.
  ServiceInstances(std::string service, std::string instance, double alive_s = 5.0, std::size_t max_instances = 16);

  // This process is one of them (the fitter): always alive, never named as the other.
  void set_own(ServiceInstance own);

  // A STATUS on the name's channel received at recv_us. When it shows a second instance alive at
  // the same time as another (one not named together before), the words naming both; else nullopt.
  // A STATUS of another service or instance name is ignored.
  std::optional<std::string> heard(const status_t& status, std::int64_t recv_us);

  // Instances heard within alive_s of now_us (the own one included).
  std::vector<ServiceInstance> alive(std::int64_t now_us) const;
  std::int64_t collisions() const { return collisions_; }  // pairs named so far

 private:
  std::string service_, instance_;
  std::int64_t alive_us_;
  std::size_t max_;
  std::vector<ServiceInstance> list_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> named_;  // session pairs said
  std::int64_t collisions_ = 0;
};

}  // namespace spindown
