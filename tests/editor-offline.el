;;; tests/editor-offline.el --- tools/luv-physics.el without SLIME, run by tools/editor-test  -*- lexical-binding: t -*-

;; Run in `emacs -Q --batch' with only tools/luv-physics.el loaded (no SLIME on
;; the load path).  LUV_COPY names a copy of physics.org beside a luv-physics.asd.
;; The jumps read the page's text; reloading says what it needs.

;;; Code:

(require 'cl-lib)

(let ((passed 0) (failed 0))
  (cl-flet ((check (name ok &rest detail)
              (if ok
                  (progn (cl-incf passed) (message "editor-test: ok: %s" name))
                (cl-incf failed)
                (message "editor-test: FAILED: %s %S" name detail)))
            (line () (buffer-substring-no-properties (line-beginning-position) (line-end-position))))
    (condition-case err
        (progn
          (check "without SLIME the mode loads and starts" (and (not (featurep 'slime))
                                                                (progn (find-file (getenv "LUV_COPY")) luv-physics-mode)))
          (goto-char (point-min))
          (re-search-forward "^:CUSTOM_ID: BSOZ3U$")
          (cl-letf (((symbol-function 'completing-read)
                     (lambda (_prompt collection &rest _)
                       (car (cl-find-if (lambda (c) (string-prefix-p "definition-anchor " (car c))) collection)))))
            (call-interactively #'luv-physics-definitions))
          (check "without SLIME, anchor -> definition reads the page"
                 (string-prefix-p "(defun definition-anchor (name" (line)) (line))
          (goto-char (point-min))
          (re-search-forward "(step-physics-world w)")
          (backward-char 3)
          (call-interactively #'luv-physics-page-definition)
          (check "without SLIME, symbol -> page reads the page"
                 (string-prefix-p "(defun step-physics-world (world" (line)) (line))
          (check "without SLIME, reloading says what it needs"
                 (string-match-p "needs SLIME"
                                 (condition-case e (progn (luv-physics-reload-section nil) "")
                                   (user-error (error-message-string e)))))
          ;; C-c ' and C-c ' again, with no edit, then C-x C-s: the file is byte for byte the same
          (let ((file (getenv "LUV_COPY"))
                (bytes (lambda (file) (with-temp-buffer
                                        (set-buffer-multibyte nil)
                                        (insert-file-contents-literally file)
                                        (buffer-string)))))
            (let ((before (funcall bytes file))
                  (blocks '()))
              (dolist (at '("^(defun substep-phase (world)" "^(define-claim \"OWNJGP\" reload-keeps-changed-parameters"))
                (goto-char (point-min))
                (re-search-forward at)
                (forward-line 2)
                (org-edit-special)
                (push (buffer-name) blocks)
                (org-edit-src-exit)
                (set-buffer-modified-p t)
                (let ((inhibit-message t)) (save-buffer)))
              (check "C-c ' then C-c ' with no edit leaves an engine block and a claim block byte for byte"
                     (and (= 2 (length blocks)) (string= before (funcall bytes file)))
                     blocks org-src-preserve-indentation org-edit-src-content-indentation))
            ;; every block: what C-c ' shows, written back as C-c ' writes it, is the block's text
            (let ((changed '()) (count 0))
              (org-babel-map-src-blocks nil
                ;; the page holds the escaped text, the edit buffer shows it unescaped
                (let ((stored (buffer-substring-no-properties beg-body end-body)))
                  (setq count (1+ count))
                  (unless (string= (org-escape-code-in-string (org-unescape-code-in-string stored)) stored)
                    (push (line-number-at-pos beg-block) changed))))
              (check (format "all %d blocks come back from an edit buffer as they are" count)
                     (and (> count 400) (null changed))
                     (reverse changed)))))
      (error (check "the checks without SLIME ran to the end" nil (error-message-string err)))))
  (message "editor-test: without SLIME %d passed, %d failed" passed failed)
  (kill-emacs (if (and (zerop failed) (> passed 0)) 0 1)))

;;; editor-offline.el ends here
