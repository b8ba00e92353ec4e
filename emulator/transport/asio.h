// The one Asio include of the project (ARCHITECTURE house style 9; FACTS
// "Toolchain"): Boost 1.74's Asio needs <utility> before its headers under
// C++20 with g++ 12. Every Asio user includes this header and no other.
#ifndef MOCO_TRANSPORT_ASIO_H_
#define MOCO_TRANSPORT_ASIO_H_

#include <utility>

#include <boost/asio.hpp>

namespace moco::transport {
namespace asio = boost::asio;
using ErrorCode = boost::system::error_code;
}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_ASIO_H_
