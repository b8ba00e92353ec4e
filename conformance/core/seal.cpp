// SHA-256, Ed25519, zlib and base64 for certificates (seal.h).
#include "conformance/core/seal.h"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <zlib.h>

#include <array>
#include <memory>

namespace moco::conformance {
namespace {

struct PkeyFree {
  void operator()(EVP_PKEY* k) const { EVP_PKEY_free(k); }
};
struct BioFree {
  void operator()(BIO* b) const { BIO_free(b); }
};
struct MdCtxFree {
  void operator()(EVP_MD_CTX* c) const { EVP_MD_CTX_free(c); }
};
using Pkey = std::unique_ptr<EVP_PKEY, PkeyFree>;
using Bio = std::unique_ptr<BIO, BioFree>;
using MdCtx = std::unique_ptr<EVP_MD_CTX, MdCtxFree>;

// OpenSSL's last error as text, the queue cleared.
std::string OpensslError(const char* what) {
  const unsigned long e = ERR_get_error();
  ERR_clear_error();
  std::string s = what;
  if (e != 0) {
    char buf[256];
    ERR_error_string_n(e, buf, sizeof buf);
    s += std::string(" (") + buf + ")";
  }
  return s;
}

std::string BioText(BIO* bio) {
  char* data = nullptr;
  const long n = BIO_get_mem_data(bio, &data);
  return n > 0 ? std::string(data, static_cast<size_t>(n)) : std::string();
}

Bio MemoryOf(std::string_view text) {
  return Bio(BIO_new_mem_buf(text.data(), static_cast<int>(text.size())));
}

Pkey ReadPrivate(std::string_view pem, std::string* error) {
  if (pem.size() > (1u << 16)) {
    *error = "the key file is too long to be a key";
    return nullptr;
  }
  Bio bio = MemoryOf(pem);
  Pkey k(PEM_read_bio_PrivateKey(bio.get(), nullptr, nullptr, nullptr));
  if (!k || EVP_PKEY_get_id(k.get()) != EVP_PKEY_ED25519) {
    ERR_clear_error();
    *error = "not an Ed25519 private key in PEM (make one with 'mococheck keygen')";
    return nullptr;
  }
  return k;
}

constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

}  // namespace

std::string Sha256Hex(std::string_view bytes) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> md{};
  unsigned int n = 0;
  EVP_Digest(bytes.data(), bytes.size(), md.data(), &n, EVP_sha256(), nullptr);
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < n; ++i) {
    out.push_back(kHex[md[i] >> 4]);
    out.push_back(kHex[md[i] & 15]);
  }
  return out;
}

std::string Base64(std::string_view bytes) {
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  auto at = [&](size_t k) { return static_cast<uint32_t>(static_cast<unsigned char>(bytes[k])); };
  for (; i + 3 <= bytes.size(); i += 3) {
    const uint32_t v = at(i) << 16 | at(i + 1) << 8 | at(i + 2);
    for (int s = 18; s >= 0; s -= 6) out.push_back(kAlphabet[(v >> s) & 63]);
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = at(i) << 16;
    out += {kAlphabet[v >> 18], kAlphabet[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = at(i) << 16 | at(i + 1) << 8;
    out += {kAlphabet[v >> 18], kAlphabet[(v >> 12) & 63], kAlphabet[(v >> 6) & 63], '='};
  }
  return out;
}

std::optional<std::string> FromBase64(std::string_view text) {
  if (text.size() % 4 != 0) return std::nullopt;
  std::array<int, 256> value{};
  value.fill(-1);
  for (int i = 0; i < 64; ++i) value[static_cast<unsigned char>(kAlphabet[i])] = i;
  std::string out;
  out.reserve(text.size() / 4 * 3);
  for (size_t i = 0; i < text.size(); i += 4) {
    const bool last = i + 4 == text.size();
    int pad = 0;
    uint32_t v = 0;
    for (size_t k = 0; k < 4; ++k) {
      const char c = text[i + k];
      if (c == '=' && last && k >= 2) {
        ++pad;
        v <<= 6;
        continue;
      }
      const int d = value[static_cast<unsigned char>(c)];
      if (d < 0 || pad > 0) return std::nullopt;
      v = v << 6 | static_cast<uint32_t>(d);
    }
    out.push_back(static_cast<char>(v >> 16));
    if (pad < 2) out.push_back(static_cast<char>((v >> 8) & 0xFF));
    if (pad < 1) out.push_back(static_cast<char>(v & 0xFF));
  }
  // Canonical only: the bits padding leaves over must be zero (one text per value).
  if (Base64(out) != text) return std::nullopt;
  return out;
}

std::string Deflate(std::string_view bytes) {
  uLongf n = compressBound(static_cast<uLong>(bytes.size()));
  std::string out(n, '\0');
  compress2(reinterpret_cast<Bytef*>(out.data()), &n, reinterpret_cast<const Bytef*>(bytes.data()),
            static_cast<uLong>(bytes.size()), Z_BEST_COMPRESSION);
  out.resize(n);
  return out;
}

std::optional<std::string> Inflate(std::string_view compressed, size_t size, std::string* error) {
  std::string out(size, '\0');
  z_stream z{};
  if (inflateInit(&z) != Z_OK) {
    *error = "zlib could not start";
    return std::nullopt;
  }
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(compressed.data()));
  z.avail_in = static_cast<uInt>(compressed.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = inflate(&z, Z_FINISH);
  const size_t produced = z.total_out;
  const bool all_input = z.avail_in == 0;
  inflateEnd(&z);
  if (rc != Z_STREAM_END || produced != size || !all_input) {
    *error = rc == Z_STREAM_END || rc == Z_BUF_ERROR
                 ? "its length is not the " + std::to_string(size) + " bytes its header gives"
                 : "the compressed data is damaged";
    return std::nullopt;
  }
  return out;
}

std::optional<KeyPair> GenerateKeyPair(std::string* error) {
  Pkey k(EVP_PKEY_Q_keygen(nullptr, nullptr, "ED25519"));
  if (!k) {
    *error = OpensslError("could not make an Ed25519 key");
    return std::nullopt;
  }
  Bio priv(BIO_new(BIO_s_mem())), pub(BIO_new(BIO_s_mem()));
  if (PEM_write_bio_PrivateKey(priv.get(), k.get(), nullptr, nullptr, 0, nullptr, nullptr) != 1 ||
      PEM_write_bio_PUBKEY(pub.get(), k.get()) != 1) {
    *error = OpensslError("could not write the key as PEM");
    return std::nullopt;
  }
  return KeyPair{BioText(priv.get()), BioText(pub.get())};
}

std::optional<std::string> PublicKeyOf(std::string_view private_pem, std::string* error) {
  Pkey k = ReadPrivate(private_pem, error);
  if (!k) return std::nullopt;
  Bio pub(BIO_new(BIO_s_mem()));
  if (PEM_write_bio_PUBKEY(pub.get(), k.get()) != 1) {
    *error = OpensslError("could not write the public key");
    return std::nullopt;
  }
  return BioText(pub.get());
}

std::optional<std::string> RawPublicKey(std::string_view public_pem, std::string* error) {
  if (public_pem.size() > (1u << 16)) {
    *error = "the key file is too long to be a key";
    return std::nullopt;
  }
  Bio bio = MemoryOf(public_pem);
  Pkey k(PEM_read_bio_PUBKEY(bio.get(), nullptr, nullptr, nullptr));
  if (!k || EVP_PKEY_get_id(k.get()) != EVP_PKEY_ED25519) {
    ERR_clear_error();
    *error =
        "not an Ed25519 public key in PEM (the .pub file 'mococheck keygen' writes beside the key)";
    return std::nullopt;
  }
  std::string raw(32, '\0');
  size_t n = raw.size();
  if (EVP_PKEY_get_raw_public_key(k.get(), reinterpret_cast<unsigned char*>(raw.data()), &n) != 1 ||
      n != 32) {
    *error = OpensslError("could not read the public key");
    return std::nullopt;
  }
  return raw;
}

std::optional<std::string> Sign(std::string_view private_pem, std::string_view message,
                                std::string* error) {
  Pkey k = ReadPrivate(private_pem, error);
  if (!k) return std::nullopt;
  MdCtx ctx(EVP_MD_CTX_new());
  std::string sig(64, '\0');
  size_t n = sig.size();
  if (!ctx || EVP_DigestSignInit(ctx.get(), nullptr, nullptr, nullptr, k.get()) != 1 ||
      EVP_DigestSign(ctx.get(), reinterpret_cast<unsigned char*>(sig.data()), &n,
                     reinterpret_cast<const unsigned char*>(message.data()), message.size()) != 1) {
    *error = OpensslError("could not sign");
    return std::nullopt;
  }
  sig.resize(n);
  return sig;
}

bool VerifySignature(std::string_view raw_public_key, std::string_view message,
                     std::string_view signature) {
  if (raw_public_key.size() != 32 || signature.size() != 64) return false;
  Pkey k(EVP_PKEY_new_raw_public_key(EVP_PKEY_ED25519, nullptr,
                                     reinterpret_cast<const unsigned char*>(raw_public_key.data()),
                                     raw_public_key.size()));
  MdCtx ctx(EVP_MD_CTX_new());
  const bool ok =
      k && ctx && EVP_DigestVerifyInit(ctx.get(), nullptr, nullptr, nullptr, k.get()) == 1 &&
      EVP_DigestVerify(ctx.get(), reinterpret_cast<const unsigned char*>(signature.data()),
                       signature.size(), reinterpret_cast<const unsigned char*>(message.data()),
                       message.size()) == 1;
  ERR_clear_error();
  return ok;
}

}  // namespace moco::conformance
