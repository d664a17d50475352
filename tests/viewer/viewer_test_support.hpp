#pragma once
// A tiny viewer scene and a Beast WebSocket client for the viewer tests (header-only:
// CMake compiles only tests/<module>/*_test.cpp).
#include <chrono>
#include <string>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>

#include "sflsh/viewer/viewer_scene.hpp"

namespace sflsh::viewer::test {

/// Two triangles (4 vertices) in the box [-1, 1]^3, one object "probe", one tool "probe".
ViewerScene tiny_scene();

/// A blocking WebSocket client of a viewer server on 127.0.0.1.
class Client {
 public:
  explicit Client(int port);
  /// The next message (text or binary), waiting at most 5 s (throws after).
  std::string read(bool* text = nullptr);
  void send(const std::string& text);

 private:
  boost::asio::io_context ioc_;
  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_{ioc_};
};

inline ViewerScene tiny_scene() {
  ViewerScene s;
  s.faces.resize(2, 3);
  s.faces << 0, 1, 2, 0, 2, 3;
  s.rest.resize(4, 3);
  s.rest << 0, 0, 0, 0.5, 0, 0, 0.5, 0.5, 0, 0, 0.5, 0;
  s.body_names = {"body"};
  s.body_offsets = {0, 4};
  s.num_joints = 0;
  ViewerObject probe;
  probe.name = "probe";
  probe.shape = "sphere";
  probe.kind = "tool";
  probe.vertices = s.rest;
  probe.faces = s.faces;
  s.objects = {probe};
  s.tools = {"probe"};
  s.tool_objects = {0};
  s.box_min = Vec3::Constant(-1);
  s.box_max = Vec3::Constant(1);
  s.legend_max = 0.01;
  return s;
}

inline Client::Client(int port) {
  namespace net = boost::asio;
  auto& tcp = boost::beast::get_lowest_layer(ws_);
  tcp.expires_after(std::chrono::seconds(5));
  tcp.connect(net::ip::tcp::endpoint(net::ip::make_address("127.0.0.1"), std::uint16_t(port)));
  ws_.handshake("127.0.0.1:" + std::to_string(port), "/ws");
}

inline std::string Client::read(bool* text) {
  boost::beast::get_lowest_layer(ws_).expires_after(std::chrono::seconds(5));
  boost::beast::flat_buffer buf;
  ws_.read(buf);
  if (text) *text = ws_.got_text();
  return boost::beast::buffers_to_string(buf.data());
}

inline void Client::send(const std::string& text) {
  boost::beast::get_lowest_layer(ws_).expires_after(std::chrono::seconds(5));
  ws_.text(true);
  ws_.write(boost::asio::buffer(text));
}

}  // namespace sflsh::viewer::test
