#include "common/process.h"

#include <chrono>
#include <csignal>
#include <iostream>

namespace rgbdslam {
namespace {
std::atomic<bool> g_stop{false};  // the only global: written by the signal handler
extern "C" void onStopSignal(int) { g_stop.store(true); }
}  // namespace

std::atomic<bool>& installStopHandlers() {
  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  return g_stop;
}

int64_t utimeNow() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Expected<std::unique_ptr<lcm::LCM>> openLcm(const std::string& url) {
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good()) {
    return Error{"cannot open LCM at '" + url +
                 "' (bad URL, or no multicast route: try 'ip route add 224.0.0.0/4 dev lo')"};
  }
  return lcm;
}

RawSubscription::RawSubscription(lcm::LCM* lcm, const std::string& channel, Handler handler)
    : lcm_(lcm), handler_(std::move(handler)) {
  subscription_ = lcm_subscribe(
      lcm_->getUnderlyingLCM(), channel.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char* name, void* self) {
        const lcm::ReceiveBuffer buffer{rbuf->data, rbuf->data_size, rbuf->recv_utime};
        static_cast<RawSubscription*>(self)->handler_(&buffer, name);
      },
      this);
}

void RawSubscription::setQueueCapacity(int messages) {
  if (subscription_) lcm_subscription_set_queue_capacity(subscription_, messages);
}

RawSubscription::~RawSubscription() {
  if (subscription_) lcm_unsubscribe(lcm_->getUnderlyingLCM(), subscription_);
}

int usageError(const std::string& program, const std::string& message) {
  std::cerr << program << ": error: " << message << "\n";
  return 2;
}

}  // namespace rgbdslam
