// The primitives a certificate is sealed with (docs/certificates.md):
// SHA-256 digests, Ed25519 keys and signatures (OpenSSL's EVP API), zlib
// compression and base64 text. Every function reports a failure as a message
// and never throws.
#ifndef MOCO_CONFORMANCE_CORE_SEAL_H_
#define MOCO_CONFORMANCE_CORE_SEAL_H_

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace moco::conformance {

// The SHA-256 of `bytes` as 64 lowercase hex digits.
std::string Sha256Hex(std::string_view bytes);

// Standard base64 (RFC 4648, with padding), and back: nullopt for any
// character outside the alphabet, a bad length or bad padding.
std::string Base64(std::string_view bytes);
std::optional<std::string> FromBase64(std::string_view text);

// zlib (RFC 1950) at the best compression, and back. Inflate refuses a
// stream that is damaged or does not hold exactly `size` bytes, and never
// allocates more than `size` (which the caller bounds).
std::string Deflate(std::string_view bytes);
std::optional<std::string> Inflate(std::string_view compressed, size_t size, std::string* error);

// An Ed25519 key pair as PEM text (PKCS #8 private key, SubjectPublicKeyInfo
// public key).
struct KeyPair {
  std::string private_pem;
  std::string public_pem;
};
std::optional<KeyPair> GenerateKeyPair(std::string* error);

// The public key of a private key in PEM; nullopt (and `error`) when `pem` is
// not an Ed25519 private key.
std::optional<std::string> PublicKeyOf(std::string_view private_pem, std::string* error);

// The raw 32 bytes of an Ed25519 public key in PEM, base64; nullopt (and
// `error`) when it is not one.
std::optional<std::string> RawPublicKey(std::string_view public_pem, std::string* error);

// The Ed25519 signature (64 bytes) of `message` by the private key in PEM.
std::optional<std::string> Sign(std::string_view private_pem, std::string_view message,
                                std::string* error);

// Whether `signature` is the Ed25519 signature of `message` by the public
// key `raw_public_key` (32 bytes).
bool VerifySignature(std::string_view raw_public_key, std::string_view message,
                     std::string_view signature);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_SEAL_H_
