#pragma once
// RAII owner of one lcm_t, on LCM's C API only: lcm_publish sends from the
// caller's buffer, whereas the C++ wrapper's publish() allocates on every call.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

// lcm_t and lcm_recv_buf_t of <lcm/lcm.h>, kept out of this header
struct _lcm_t;
struct _lcm_recv_buf_t;

namespace rtfuse::transport {

// The bytes are valid only during the call. recv_utime is LCM's receive time
// (wall clock, µs).
using RawHandler = void (*)(const char* channel, const std::uint8_t* data, int size,
                            std::int64_t recv_utime, void* user);

class LcmNode {
 public:
  // url as LCM takes it ("udpm://239.255.76.67:7667?ttl=0", "memq://", ...);
  // empty means LCM's default (LCM_DEFAULT_URL). nullptr and *error set on failure.
  static std::unique_ptr<LcmNode> create(const std::string& url, std::string* error);

  ~LcmNode();
  LcmNode(const LcmNode&) = delete;
  LcmNode& operator=(const LcmNode&) = delete;

  // Readable when messages are waiting: for poll()/select() loops.
  int fd();
  // Dispatches at most one message to the handlers: >0 handled, 0 timed out, <0 error.
  int handle_timeout(int timeout_ms);
  bool publish(const char* channel, const void* data, int size);
  // channel is a regular expression, as in lcm_subscribe. Allocates: call it at
  // set-up time. Subscriptions live as long as the node.
  bool subscribe(const char* channel, RawHandler handler, void* user);

  const std::string& url() const { return url_; }
  _lcm_t* raw() { return lcm_; }

 private:
  struct Subscription {
    RawHandler handler;
    void* user;
  };
  LcmNode(_lcm_t* lcm, std::string url) : lcm_(lcm), url_(std::move(url)) {}
  // LCM's handler signature to ours; user is the Subscription.
  static void dispatch(const _lcm_recv_buf_t* rbuf, const char* channel, void* user);

  _lcm_t* lcm_;
  std::string url_;
  // unique_ptr: LCM keeps a pointer to each entry, so addresses must be stable.
  std::vector<std::unique_ptr<Subscription>> subscriptions_;
};

}  // namespace rtfuse::transport
