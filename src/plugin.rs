//! Extension points are plain registries: a list of `module::ITEM` pairs that declares each
//! module and collects its item, so a new sample generator, light selector, BSDF lobe or light
//! type is one new file plus one line here-or-there (see docs/extending.md).

/// `registry! { pub static NAME: Type = [module::ITEM, ...]; }` declares `pub mod module;` for
/// each entry and `pub static NAME: &[&Type]` holding `&module::ITEM` in listing order.
macro_rules! registry {
    ($(#[$meta:meta])* $vis:vis static $name:ident: $ty:ty = [$($module:ident :: $item:ident),* $(,)?];) => {
        $(pub mod $module;)*
        $(#[$meta])*
        $vis static $name: &[&$ty] = &[$(&$module::$item),*];
    };
}
pub(crate) use registry;
