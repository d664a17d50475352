#include "sflsh/viewer/viewer_server.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <deque>
#include <mutex>
#include <thread>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "sflsh/core/error.hpp"
#include "sflsh/viewer/web_assets.hpp"

namespace sflsh::viewer {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

constexpr std::size_t kMaxQueuedControls = 1000;
constexpr std::size_t kMaxReadBytes = 64 * 1024;

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Published {
  ViewerFrame frame;
  std::uint32_t number = 0;
  std::uint64_t seq = 0;
};

}  // namespace

class WsSession;

struct ViewerServer::Impl {
  ViewerScene scene;
  std::string scene_text;
  ViewerServerOptions options;
  net::io_context ioc;
  tcp::acceptor acceptor{ioc};
  std::thread thread;
  int port = 0;

  // Frame slot (publish -> io thread).
  std::mutex frame_mutex;
  std::shared_ptr<const Published> latest;
  std::atomic<std::uint32_t> frame_number{0};
  std::atomic<double> next_due{0.0};
  std::atomic<std::uint64_t> applied_seq{0};

  // Io thread only: the latest frame's quantized skin, the sessions, the pose checks.
  std::shared_ptr<const Published> current;
  QuantizedSkin current_skin;
  std::vector<std::weak_ptr<WsSession>> sessions;
  int driver = -1, next_id = 1;
  teleop::PoseStreamFilter filter;

  // Controls (io thread -> poll).
  std::mutex control_mutex;
  std::deque<ControlMessage> controls;

  std::atomic<int> clients{0};
  std::atomic<long> published{0}, sent{0}, frame_bytes{0}, accepted{0}, rejected{0}, connected{0};

  explicit Impl(const ViewerServerOptions& o) : options(o), filter(o.checks) {}

  void log(const std::string& line) const {
    if (!options.quiet) std::fprintf(stderr, "viewer: %s\n", line.c_str());
  }

  void accept();
  void on_new_frame();
  void add_session(const std::shared_ptr<WsSession>& s);
  void remove_session(int id);
  void on_control(int client, const std::string& text);
  void elect_driver();
};

/// One WebSocket client: the scene once, then the newest frame whenever the
/// previous write has finished; control messages read in a loop.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket socket, ViewerServer::Impl& server, int id) : ws_(std::move(socket)), srv_(server), id_(id) {}

  int id() const { return id_; }

  void run(http::request<http::string_body> req) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxReadBytes);
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->srv_.add_session(self);
      self->offer();
      self->read();
    });
  }

  /// Starts the next write if none is running: the scene, then the newest frame not yet sent.
  void offer() {
    if (writing_ || closed_) return;
    if (!scene_sent_) {
      scene_sent_ = true;
      ws_.text(true);
      write(srv_.scene_text, false);
      return;
    }
    const auto& cur = srv_.current;
    if (!cur || cur->number == sent_number_) return;
    sent_number_ = cur->number;
    FrameEnvelope e;
    e.number = cur->number;
    e.seq = cur->seq;
    e.driver = srv_.driver == id_;
    e.clients = srv_.clients.load();
    ws_.binary(true);
    write(encode_frame(cur->frame, srv_.current_skin, srv_.scene, e, &last_sent_), true);
  }

 private:
  void write(std::string message, bool frame) {
    writing_ = true;
    out_ = std::move(message);
    ws_.async_write(net::buffer(out_), [self = shared_from_this(), frame](beast::error_code ec, std::size_t n) {
      self->writing_ = false;
      if (ec) return self->close();
      ++self->srv_.sent;
      if (frame) self->srv_.frame_bytes += long(n);
      self->offer();
    });
  }

  void read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return self->close();
      if (self->ws_.got_text())
        self->srv_.on_control(self->id_, beast::buffers_to_string(self->in_.data()));
      else {
        ++self->srv_.rejected;
        self->srv_.log("client " + std::to_string(self->id_) + ": ignored a binary message (controls are JSON text)");
      }
      self->in_.consume(self->in_.size());
      self->read();
    });
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    srv_.remove_session(id_);
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
  }

  websocket::stream<beast::tcp_stream> ws_;
  ViewerServer::Impl& srv_;
  int id_;
  beast::flat_buffer in_;
  std::string out_;
  bool writing_ = false, scene_sent_ = false, closed_ = false;
  std::uint32_t sent_number_ = 0;
  QuantizedSkin last_sent_;
};

namespace {

/// One HTTP connection: serves the page's files; hands a WebSocket upgrade over to WsSession.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, ViewerServer::Impl& server) : stream_(std::move(socket)), srv_(server) {}

  void read() {
    req_ = {};
    stream_.expires_after(std::chrono::seconds(60));
    http::async_read(stream_, buf_, req_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return;
      self->respond();
    });
  }

 private:
  void respond() {
    if (websocket::is_upgrade(req_)) {
      stream_.expires_never();
      const int id = srv_.next_id++;
      std::make_shared<WsSession>(stream_.release_socket(), srv_, id)->run(std::move(req_));
      return;
    }
    const bool keep_alive = req_.keep_alive();
    const std::string target(req_.target());
    const WebAsset* asset = find_web_asset(target);
    if ((req_.method() != http::verb::get && req_.method() != http::verb::head) || !asset) {
      auto res = std::make_shared<http::response<http::string_body>>(
          asset ? http::status::method_not_allowed : http::status::not_found, req_.version());
      res->set(http::field::content_type, "text/plain; charset=utf-8");
      res->body() = asset ? "only GET\n" : "not found: " + target.substr(0, 200) + "\n";
      res->keep_alive(keep_alive);
      res->prepare_payload();
      http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
        self->after_write(ec, res->keep_alive());
      });
      return;
    }
    auto res = std::make_shared<http::response<http::span_body<const char>>>(http::status::ok, req_.version());
    res->set(http::field::content_type, std::string(asset->content_type));
    res->set(http::field::cache_control, "no-cache");
    res->body() = {asset->body.data(), asset->body.size()};
    res->keep_alive(keep_alive);
    res->prepare_payload();
    if (req_.method() == http::verb::head) res->body() = {};
    http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
      self->after_write(ec, res->keep_alive());
    });
  }

  void after_write(beast::error_code ec, bool keep_alive) {
    if (ec || !keep_alive) {
      stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    read();
  }

  beast::tcp_stream stream_;
  ViewerServer::Impl& srv_;
  beast::flat_buffer buf_;
  http::request<http::string_body> req_;
};

}  // namespace

void ViewerServer::Impl::accept() {
  acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
    if (!ec) std::make_shared<HttpSession>(std::move(socket), *this)->read();
    if (acceptor.is_open()) accept();
  });
}

void ViewerServer::Impl::on_new_frame() {
  std::shared_ptr<const Published> p;
  {
    std::lock_guard<std::mutex> lock(frame_mutex);
    p = latest;
  }
  if (!p || (current && current->number == p->number)) return;
  current_skin = quantize(p->frame, scene);
  current = p;
  for (auto& w : sessions)
    if (auto s = w.lock()) s->offer();
}

void ViewerServer::Impl::add_session(const std::shared_ptr<WsSession>& s) {
  sessions.push_back(s);
  ++clients;
  ++connected;
  log("client " + std::to_string(s->id()) + " connected (" + std::to_string(clients.load()) + " now)");
  elect_driver();
}

void ViewerServer::Impl::remove_session(int id) {
  sessions.erase(std::remove_if(sessions.begin(), sessions.end(),
                                [id](const std::weak_ptr<WsSession>& w) {
                                  auto s = w.lock();
                                  return !s || s->id() == id;
                                }),
                 sessions.end());
  clients = int(sessions.size());
  log("client " + std::to_string(id) + " left (" + std::to_string(clients.load()) + " now)");
  elect_driver();
}

void ViewerServer::Impl::elect_driver() {
  const int d = sessions.empty() ? -1 : sessions.front().lock() ? sessions.front().lock()->id() : -1;
  if (d == driver) return;
  driver = d;
  filter = teleop::PoseStreamFilter(options.checks);  // a new device session
  if (d >= 0) log("client " + std::to_string(d) + " drives");
}

void ViewerServer::Impl::on_control(int client, const std::string& text) {
  const std::string who = "client " + std::to_string(client) + ": ";
  ControlParse parsed = parse_control_message(text);
  if (!parsed.message) {
    ++rejected;
    return log(who + "ignored a control message: " + parsed.error);
  }
  ControlMessage& m = *parsed.message;
  if (client != driver) {
    ++rejected;
    return log(who + "ignored '" + to_string(m.type) + "': client " + std::to_string(driver) + " drives, this one watches");
  }
  if (m.type == ControlType::kTool) {
    if (m.tool >= int(scene.tools.size())) {
      ++rejected;
      return log(who + "ignored a tool pose: tool " + std::to_string(m.tool) + ", the scene has " +
                 std::to_string(scene.tools.size()) + " drivable tool(s)");
    }
    teleop::PoseMessage pm;
    pm.sequence = m.seq;
    pm.sample = m.pose;
    std::string detail;
    if (const auto reason = filter.check(pm, &detail)) {
      ++rejected;
      return log(who + "ignored a tool pose (" + teleop::to_string(*reason) + "): " + detail + "; last good pose kept");
    }
    m.pose = filter.last_good()->sample;
  }
  // After a reset the tool starts over at its start pose: the page's next
  // poses start from there, a new device session for the jump checks.
  if (m.type == ControlType::kReset && scene.can_reset) filter = teleop::PoseStreamFilter(options.checks);
  m.client = client;
  ++accepted;
  std::lock_guard<std::mutex> lock(control_mutex);
  if (controls.size() >= kMaxQueuedControls) controls.pop_front();
  controls.push_back(m);
}

ViewerServer::ViewerServer(ViewerScene scene, const ViewerServerOptions& options) : impl_(std::make_unique<Impl>(options)) {
  require(options.fps > 0 && options.fps <= 60, "viewer: fps ", options.fps, ": expected a display rate in (0, 60]");
  require(options.port >= 0 && options.port <= 65535, "viewer: port ", options.port, ": expected 0..65535");
  const std::string problem = web_assets_problem();
  require(problem.empty(), "viewer: ", problem);
  impl_->scene = std::move(scene);
  impl_->scene_text = scene_json(impl_->scene);
  beast::error_code ec;
  const net::ip::address address = net::ip::make_address(options.bind, ec);
  require(!ec, "viewer: bind address '", options.bind, "': expected an IP address (e.g. 127.0.0.1)");
  const tcp::endpoint endpoint(address, std::uint16_t(options.port));
  auto& a = impl_->acceptor;
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  require(!ec, "viewer: cannot listen on ", options.bind, ":", options.port, ": ", ec.message());
  impl_->port = a.local_endpoint().port();
  if (!address.is_loopback())
    std::fprintf(stderr,
                 "viewer: WARNING: serving on %s:%d, not loopback: anyone who can reach this address can watch and "
                 "drive the simulation (no authentication)\n",
                 options.bind.c_str(), impl_->port);
  impl_->accept();
  impl_->thread = std::thread([this] { impl_->ioc.run(); });
}

ViewerServer::~ViewerServer() {
  impl_->ioc.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
  impl_->sessions.clear();
}

int ViewerServer::port() const { return impl_->port; }

std::string ViewerServer::url() const {
  const std::string& b = impl_->options.bind;
  const bool v6 = b.find(':') != std::string::npos;
  return "http://" + (v6 ? "[" + b + "]" : b) + ":" + std::to_string(impl_->port) + "/";
}

const ViewerScene& ViewerServer::scene() const { return impl_->scene; }

bool ViewerServer::frame_due() const { return now_s() >= impl_->next_due.load(); }

void ViewerServer::publish(ViewerFrame frame) {
  const double now = now_s(), period = 1.0 / impl_->options.fps;
  // The next due time advances by one period (a steady rate), or restarts
  // from now when the publisher fell behind by more than a period.
  const double due = impl_->next_due.load();
  impl_->next_due = (now - due > period) ? now + period : due + period;
  auto p = std::make_shared<Published>();
  p->frame = std::move(frame);
  p->number = ++impl_->frame_number;
  p->seq = impl_->applied_seq.load();
  {
    std::lock_guard<std::mutex> lock(impl_->frame_mutex);
    impl_->latest = std::move(p);
  }
  ++impl_->published;
  net::post(impl_->ioc, [impl = impl_.get()] { impl->on_new_frame(); });
}

std::vector<ControlMessage> ViewerServer::poll() {
  std::vector<ControlMessage> out;
  {
    std::lock_guard<std::mutex> lock(impl_->control_mutex);
    out.assign(impl_->controls.begin(), impl_->controls.end());
    impl_->controls.clear();
  }
  if (!out.empty()) impl_->applied_seq = out.back().seq;
  return out;
}

int ViewerServer::num_clients() const { return impl_->clients.load(); }

ViewerCounters ViewerServer::counters() const {
  ViewerCounters c;
  c.frames_published = impl_->published;
  c.messages_sent = impl_->sent;
  c.frame_bytes_sent = impl_->frame_bytes;
  c.controls_accepted = impl_->accepted;
  c.controls_rejected = impl_->rejected;
  c.clients_connected = impl_->connected;
  return c;
}

}  // namespace sflsh::viewer
