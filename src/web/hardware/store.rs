//! The Hardware page's recordings in IndexedDB: each recording's description
//! ([`RecordingMeta`], JSON) in one object store and its CSV text in chunks in another, keyed by
//! `[recording id, chunk index]`. A chunk and the description that counts it are written in one
//! transaction, so after a crash the description never counts a chunk that is not there.

use js_sys::{Array, Function, Promise};
use wasm_bindgen::{JsCast, JsValue};
use web_sys::{
    IdbDatabase, IdbKeyRange, IdbObjectStore, IdbRequest, IdbTransaction, IdbTransactionMode,
};

use crate::hardware::recording::RecordingMeta;
use crate::web::js::describe;

const DATABASE: &str = "cutlab-hardware";
const VERSION: u32 = 1;
const RECORDINGS: &str = "recordings";
const CHUNKS: &str = "recording-chunks";

/// Waits for `request` and gives its result.
async fn done(request: &IdbRequest) -> Result<JsValue, String> {
    let promise = Promise::new(&mut |resolve: Function, reject: Function| {
        request.set_onsuccess(Some(&resolve));
        request.set_onerror(Some(&reject));
    });
    match wasm_bindgen_futures::JsFuture::from(promise).await {
        Ok(_) => request.result().map_err(|e| describe(&e)),
        Err(_) => Err(match request.error() {
            Ok(Some(e)) => describe(&e.into()),
            _ => "the request failed".to_string(),
        }),
    }
}

/// Waits for `transaction` to commit.
async fn committed(transaction: &IdbTransaction) -> Result<(), String> {
    let promise = Promise::new(&mut |resolve: Function, reject: Function| {
        transaction.set_oncomplete(Some(&resolve));
        transaction.set_onerror(Some(&reject));
        transaction.set_onabort(Some(&reject));
    });
    match wasm_bindgen_futures::JsFuture::from(promise).await {
        Ok(_) => Ok(()),
        Err(_) => Err(transaction.error().map_or_else(
            || "the transaction was aborted".to_string(),
            |e| describe(&e.into()),
        )),
    }
}

fn chunk_key(id: u64, index: u32) -> JsValue {
    Array::of2(
        &JsValue::from_f64(id as f64),
        &JsValue::from_f64(f64::from(index)),
    )
    .into()
}

fn chunk_range(id: u64) -> Result<IdbKeyRange, String> {
    IdbKeyRange::bound(&chunk_key(id, 0), &chunk_key(id, u32::MAX)).map_err(|e| describe(&e))
}

/// The recordings database.
#[derive(Clone)]
pub struct Store {
    db: IdbDatabase,
}

impl Store {
    /// Opens (creating on first use) the database.
    pub async fn open() -> Result<Store, String> {
        let factory = leptos::prelude::window()
            .indexed_db()
            .map_err(|e| describe(&e))?
            .ok_or_else(|| "this browser offers no IndexedDB".to_string())?;
        let request = factory
            .open_with_u32(DATABASE, VERSION)
            .map_err(|e| describe(&e))?;
        // Creating the stores happens in the upgrade, before success.
        let upgrade_request = request.clone();
        let on_upgrade = wasm_bindgen::closure::Closure::once_into_js(move || {
            if let Ok(result) = upgrade_request.result() {
                let db: IdbDatabase = result.unchecked_into();
                let names = db.object_store_names();
                if !names.contains(RECORDINGS) {
                    let _ = db.create_object_store(RECORDINGS);
                }
                if !names.contains(CHUNKS) {
                    let _ = db.create_object_store(CHUNKS);
                }
            }
        });
        request.set_onupgradeneeded(Some(on_upgrade.unchecked_ref()));
        let db: IdbDatabase = done(&request).await?.unchecked_into();
        Ok(Store { db })
    }

    fn stores(
        &self,
        mode: IdbTransactionMode,
    ) -> Result<(IdbTransaction, IdbObjectStore, IdbObjectStore), String> {
        let names = Array::of2(&RECORDINGS.into(), &CHUNKS.into());
        let transaction = self
            .db
            .transaction_with_str_sequence_and_mode(&names, mode)
            .map_err(|e| describe(&e))?;
        let recordings = transaction
            .object_store(RECORDINGS)
            .map_err(|e| describe(&e))?;
        let chunks = transaction.object_store(CHUNKS).map_err(|e| describe(&e))?;
        Ok((transaction, recordings, chunks))
    }

    /// Every recording's description, oldest first (unreadable ones are skipped and counted).
    pub async fn list(&self) -> Result<(Vec<RecordingMeta>, usize), String> {
        let (_, recordings, _) = self.stores(IdbTransactionMode::Readonly)?;
        let values = done(&recordings.get_all().map_err(|e| describe(&e))?).await?;
        let mut metas = Vec::new();
        let mut unreadable = 0;
        for value in Array::from(&values).iter() {
            match value.as_string().map(|t| RecordingMeta::from_json(&t)) {
                Some(Ok(m)) => metas.push(m),
                _ => unreadable += 1,
            }
        }
        metas.sort_by_key(|m| m.id);
        Ok((metas, unreadable))
    }

    /// Writes `meta` and, if given, one chunk of its text, in one transaction.
    pub async fn put(
        &self,
        meta: &RecordingMeta,
        chunk: Option<(u32, String)>,
    ) -> Result<(), String> {
        let (transaction, recordings, chunks) = self.stores(IdbTransactionMode::Readwrite)?;
        if let Some((index, text)) = chunk {
            chunks
                .put_with_key(&JsValue::from_str(&text), &chunk_key(meta.id, index))
                .map_err(|e| describe(&e))?;
        }
        recordings
            .put_with_key(
                &JsValue::from_str(&meta.to_json()),
                &JsValue::from_f64(meta.id as f64),
            )
            .map_err(|e| describe(&e))?;
        committed(&transaction).await
    }

    /// The chunks of recording `id`, in order: joined, the CSV file.
    pub async fn chunks(&self, id: u64) -> Result<Array, String> {
        let (_, _, chunks) = self.stores(IdbTransactionMode::Readonly)?;
        let request = chunks
            .get_all_with_key(&chunk_range(id)?.into())
            .map_err(|e| describe(&e))?;
        Ok(Array::from(&done(&request).await?))
    }

    /// Deletes recording `id` and its chunks.
    pub async fn delete(&self, id: u64) -> Result<(), String> {
        let (transaction, recordings, chunks) = self.stores(IdbTransactionMode::Readwrite)?;
        chunks
            .delete(&chunk_range(id)?.into())
            .map_err(|e| describe(&e))?;
        recordings
            .delete(&JsValue::from_f64(id as f64))
            .map_err(|e| describe(&e))?;
        committed(&transaction).await
    }
}
