// Every component library compiles this file too, so a component whose sources are all templates
// in headers still yields a valid static library.
namespace rotorid::internal {
inline constexpr int kModuleAnchor = 0;
}  // namespace rotorid::internal
