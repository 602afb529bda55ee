#include "transport/lcm_node.hpp"

#include <lcm/lcm.h>

#include <string_view>
#include <utility>

namespace rtfuse::transport {
namespace {

std::string create_failure_message(const std::string& url) {
  const std::string shown = url.empty() ? "(LCM's default, LCM_DEFAULT_URL)" : "'" + url + "'";
  std::string message = "cannot create LCM for URL " + shown + ": ";
  const std::string_view u(url);
  if (u.empty() || u.substr(0, 7) == "udpm://") {
    message +=
        "UDP multicast needs a route for 224.0.0.0/4 on a live interface. For a single "
        "machine: 'sudo ip route add 224.0.0.0/4 dev lo' (and 'sudo ip link set lo multicast "
        "on'); on a network check that the interface is up and routes multicast. Use ttl=0 to "
        "keep traffic on this host, ttl=1 for the local subnet. LCM printed the system error "
        "above.";
  } else {
    message +=
        "unknown provider or malformed URL; LCM understands udpm://, memq://, tcpq:// and "
        "file:// (e.g. 'udpm://239.255.76.67:7667?ttl=0', 'memq://').";
  }
  return message;
}

}  // namespace

void LcmNode::dispatch(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  const auto* sub = static_cast<const Subscription*>(user);
  sub->handler(channel, static_cast<const std::uint8_t*>(rbuf->data),
               static_cast<int>(rbuf->data_size), rbuf->recv_utime, sub->user);
}

std::unique_ptr<LcmNode> LcmNode::create(const std::string& url, std::string* error) {
  lcm_t* lcm = lcm_create(url.empty() ? nullptr : url.c_str());
  if (lcm == nullptr) {
    if (error != nullptr) *error = create_failure_message(url);
    return nullptr;
  }
  return std::unique_ptr<LcmNode>(new LcmNode(lcm, url));
}

LcmNode::~LcmNode() { lcm_destroy(lcm_); }

int LcmNode::fd() { return lcm_get_fileno(lcm_); }

int LcmNode::handle_timeout(int timeout_ms) { return lcm_handle_timeout(lcm_, timeout_ms); }

bool LcmNode::publish(const char* channel, const void* data, int size) {
  if (channel == nullptr || size < 0 || (size > 0 && data == nullptr)) return false;
  return lcm_publish(lcm_, channel, data, static_cast<unsigned int>(size)) == 0;
}

bool LcmNode::subscribe(const char* channel, RawHandler handler, void* user) {
  if (channel == nullptr || handler == nullptr) return false;
  subscriptions_.push_back(std::make_unique<Subscription>(Subscription{handler, user}));
  if (lcm_subscribe(lcm_, channel, &LcmNode::dispatch, subscriptions_.back().get()) == nullptr) {
    subscriptions_.pop_back();
    return false;
  }
  return true;
}

}  // namespace rtfuse::transport
