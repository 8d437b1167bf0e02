#include "spindown/lab_traffic.hpp"

#include <algorithm>
#include <fmt/format.h>

#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/message_auth.hpp"
#include "spindown/message_gate.hpp"
#include "spindown/session_id.hpp"

namespace spindown {

namespace {

std::string join(const std::set<std::string>& items, std::size_t max_shown = 6) {
  std::string out;
  std::size_t n = 0;
  for (const auto& s : items) {
    if (n++ == max_shown) return out + fmt::format(", … ({} in all)", items.size());
    out += (out.empty() ? "" : ", ") + s;
  }
  return out;
}

}  // namespace

void LabTraffic::add(std::string_view channel, const void* data, std::int64_t size, std::int64_t recv_us,
                     const status_t* status, const LabKey* key) {
  const auto parsed = parse_channel(channel);
  MessageTrailer t;
  if (!parsed || !read_message_trailer(data, size, t)) return;
  ++messages_;
  const std::string lab(t.lab);
  auto lab_it = labs_.find(lab);
  if (lab_it == labs_.end()) {
    if (labs_.size() >= max_) return;
    lab_it = labs_.emplace(lab, Lab{}).first;
  }
  Lab& l = lab_it->second;
  ++l.messages;
  const std::string host = t.source_host.empty() ? std::string("(no host named)") : shown_name(t.source_host);
  std::string sender = parsed->bench;
  if (status) sender = fmt::format("{} {}", shown_name(status->service), shown_name(status->instance));
  else if (parsed->kind == ChannelKind::sample || parsed->kind == ChannelKind::config) sender = "bridge " + parsed->bench;
  else if (parsed->kind != ChannelKind::status) sender = "fitter (" + std::string(channel_suffix(parsed->kind)) + ")";
  const auto note = [&](Lab& entry) {
    if (entry.senders.count(host) || entry.senders.size() < max_) {
      auto& set = entry.senders[host];
      if (set.size() < 16) set.insert(sender);
    }
  };
  note(l);
  const std::string to(t.sent_to);
  if (destinations_.count(to) || destinations_.size() < max_) {
    Lab& d = destinations_[to];
    ++d.messages;
    note(d);
  }

  if (key) {
    const AuthCheck a = verify_message(channel, data, size, *key);
    if (a.status != AuthStatus::valid) {
      const std::string kind(auth_status_name(a.status));
      ++auth_[kind];
      if (auth_hosts_[kind].size() < 16) auth_hosts_[kind].insert(host);
    }
  }

  const std::string prefix = lab + "\n" + to + "\n";
  if (parsed->kind == ChannelKind::sample) {
    auto& list = sample_sources_[prefix + std::string(channel)];
    auto it = std::find_if(list.begin(), list.end(),
                           [&](const Source& s) { return s.session == t.source_session && s.host == t.source_host; });
    if (it == list.end()) {
      if (list.size() < 8) list.push_back({std::string(t.source_host), t.source_session, recv_us, recv_us});
    } else {
      it->last_us = recv_us;
    }
  }
  if (status) {
    const std::string k = prefix + status->service + "\n" + status->instance;
    auto it = services_.find(k);
    if (it == services_.end() && services_.size() < max_)
      it = services_.emplace(k, ServiceInstances(status->service, status->instance)).first;
    if (it != services_.end())
      if (auto text = it->second.heard(*status, recv_us)) collisions_[k] = *text;
  }
}

std::vector<DoctorCheck> LabTraffic::checks(const std::string& our_lab, const std::optional<LabKey>& key,
                                            const std::string& url, double listened_s, std::int64_t) const {
  std::vector<DoctorCheck> out;
  if (messages_ == 0) {
    out.push_back({"lab traffic", CheckLevel::skip,
                   fmt::format("no SPINDOWN.* message heard on {} in {:.3g} s", url, listened_s), ""});
    return out;
  }
  // Another group's traffic reaching this port (the trap of a PC that serves two labs).
  const std::string ours_to = lcm_destination(url);
  for (const auto& [to, d] : destinations_) {
    if (to.empty() || ours_to.empty() || to == ours_to || !same_port(to, ours_to)) continue;  // replayed here
    std::string who;
    for (const auto& [host, senders] : d.senders) who += fmt::format("{}host {} ({})", who.empty() ? "" : "; ", host, join(senders));
    out.push_back({"other group " + shown_name(to), CheckLevel::warn,
                   fmt::format("{} message{} sent to {} reach this PC's socket on {} (another lab's traffic: Linux hands "
                               "every group joined on a port to each socket bound to that port, so a PC that serves "
                               "two labs on one port hears both) from {}; the services count them as another lab's "
                               "and never use them",
                               d.messages, d.messages == 1 ? "" : "s", shown_name(to), ours_to, who),
                   fmt::format("give each lab its own port as well as its own group, e.g. "
                               "LCM_DEFAULT_URL=udpm://{}:{}?ttl=1 for the other lab (docs/lab-setup.md)",
                               shown_name(to.substr(0, to.find(':'))), 7668)});
  }
  // Another lab on this group and port.
  std::vector<std::string> others;
  for (const auto& [lab, l] : labs_) {
    if (lab.empty() || lab == our_lab) continue;
    std::string who;
    for (const auto& [host, senders] : l.senders) who += fmt::format("{}host {} ({})", who.empty() ? "" : "; ", host, join(senders));
    others.push_back(fmt::format("lab '{}': {} message{} from {}", shown_name(lab), l.messages,
                                 l.messages == 1 ? "" : "s", who));
  }
  const auto ours = labs_.find(our_lab);
  const std::int64_t our_messages = ours == labs_.end() ? 0 : ours->second.messages;
  if (!others.empty()) {
    std::string detail = fmt::format("another lab's traffic on {} (this PC's lab is '{}', {} of its messages heard): ", url,
                                     our_lab, our_messages);
    for (std::size_t i = 0; i < others.size(); ++i) detail += (i ? " | " : "") + others[i];
    detail += ". Each lab's services ignore the other's messages (counted as other_lab), but both labs' traffic reaches "
              "every PC that listens here";
    out.push_back({"lab traffic", CheckLevel::warn, detail,
                   "give each lab its own multicast group AND port in /etc/spindown/lcm.env, e.g. "
                   "LCM_DEFAULT_URL=udpm://239.255.76.68:7668?ttl=1 for the second lab (a PC serving both labs: Linux "
                   "hands every group joined on a port to each socket bound to that port, so a group alone does not "
                   "separate them; docs/lab-setup.md)"});
  } else {
    std::set<std::string> hosts;
    if (ours != labs_.end())
      for (const auto& [host, s] : ours->second.senders) hosts.insert(host);
    out.push_back({"lab traffic", ours == labs_.end() && labs_.count("") == 0 ? CheckLevel::warn : CheckLevel::ok,
                   fmt::format("only lab '{}' on {}: {} message{} from {} host{} ({})", our_lab, url, our_messages,
                               our_messages == 1 ? "" : "s", hosts.size(), hosts.size() == 1 ? "" : "s", join(hosts)),
                   ""});
  }
  if (const auto unnamed = labs_.find(""); unnamed != labs_.end()) {
    std::set<std::string> hosts;
    for (const auto& [host, s] : unnamed->second.senders) hosts.insert(fmt::format("{} ({})", host, join(s)));
    out.push_back({"unnamed senders", CheckLevel::warn,
                   fmt::format("{} message{} name no lab (spindown programs from before labs were named, or another "
                               "program): {}",
                               unnamed->second.messages, unnamed->second.messages == 1 ? "" : "s", join(hosts)),
                   "update spindown on those PCs (deploy/install-lab) and restart their services"});
  }
  if (key) {
    if (auth_.empty()) {
      out.push_back({"signatures", CheckLevel::ok,
                     fmt::format("every message heard is signed with this lab's key {}", key_id_text(key->id)), ""});
    } else {
      std::string detail;
      for (const auto& [kind, count] : auth_)
        detail += fmt::format("{}{} {} (from {})", detail.empty() ? "" : "; ", count, kind, join(auth_hosts_.at(kind)));
      out.push_back({"signatures", CheckLevel::warn,
                     fmt::format("messages not signed with this lab's key {}: {}; the lab's services ignore them",
                                 key_id_text(key->id), detail),
                     "give every lab PC the same key (/etc/spindown/lab.key, then deploy/install-lab so the units "
                     "load it) — or find who else sends on this group and port"});
    }
  }
  for (const auto& [k, list] : sample_sources_) {
    // Two sources whose times overlap: both sent during the listen.
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) {
        const Source& a = list[i];
        const Source& b = list[j];
        if (a.last_us < b.first_us || b.last_us < a.first_us) continue;  // one after the other: a restart
        const std::string channel = k.substr(k.rfind('\n') + 1);
        out.push_back({"two sources " + channel, CheckLevel::warn,
                       fmt::format("{} has two sources: {} and {}, both sending while the doctor listened; the fitter "
                                   "fits the first and refuses the second",
                                   channel, source_text(a.host, a.session), source_text(b.host, b.session)),
                       "two bridges use one bench id (a copied bench file?), or someone else sends on it: give each "
                       "bench its own id, stop the second bridge"});
        i = list.size();
        break;
      }
  }
  for (const auto& [k, text] : collisions_) {
    std::string name = k.substr(k.find('\n', k.find('\n') + 1) + 1);
    std::replace(name.begin(), name.end(), '\n', ' ');
    out.push_back({"instances " + name, CheckLevel::warn, text,
                   "systemctl status spindown-fitter on each lab PC: run one fitter per lab, or start the second with "
                   "--instance NAME"});
  }
  return out;
}

}  // namespace spindown
