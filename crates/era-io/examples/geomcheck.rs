fn main() {
    for a in std::env::args().skip(1) {
        match era_io::geometry::read_geometry(std::path::Path::new(&a)) {
            Ok(g) => println!("{a}: {} | systems {:?} | notes {:?}", g.summary(), g.coordinate_systems.iter().map(|c| (c.id, c.kind, c.origin)).take(3).collect::<Vec<_>>(), g.notes),
            Err(e) => println!("ERR {e}"),
        }
    }
}
