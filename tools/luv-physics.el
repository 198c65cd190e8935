;;; luv-physics.el --- read physics.org beside a running luv-physics image  -*- lexical-binding: t -*-

;; Load it with one line in your init file:
;;   (load "/path/to/luv-physics/tools/luv-physics.el")
;; Every physics.org that sits beside a luv-physics.asd then opens in
;; `luv-physics-mode'.  With SLIME connected to an image that has loaded the
;; system luv-physics/workshop (the engine and the page's tools), the keys below ask that image; without SLIME (or without a
;; connection) the jumps read the page's text instead, and reloading says what
;; it needs.
;;
;; In physics.org:
;;   C-c M-.   the definitions of the section at point (or of the [[#ANCHOR]] link
;;             at point), with completion; visits the chosen one's line on the page,
;;             with C-u in the tangled file
;;   C-c M-g   the page line where the symbol at point is defined
;;   C-c M-s   what the image knows of the section at point: definitions, claims, in a
;;             selected window that q closes
;;   C-c M-r   reload the section at point into the image (C-u: the block at point)
;;   C-c C-c   on a Lisp block of the engine: reload that block
;;   C-c M-u   tangle the page and reload every form whose text changed; buffers visiting
;;             the tangled files are reverted without a question
;;   C-c '     edit a block: the edit buffer is in the engine's package, and the block's
;;             indentation is kept (org-src-preserve-indentation), so an unedited block
;;             goes back byte for byte
;; In Lisp buffers with SLIME and in the REPL:
;;   C-c M-g   the page line where the symbol at point is defined

;;; Code:

(require 'org)
(require 'org-element)
(require 'subr-x)
(require 'cl-lib)

(defvar slime-buffer-package)
(declare-function slime-connected-p "slime")
(declare-function slime-eval "slime")
(declare-function slime-symbol-at-point "slime")
(declare-function slime-current-package "slime")

(defgroup luv-physics nil
  "Reading and editing the literate page of luv-physics beside a live image."
  :group 'tools)

(defcustom luv-physics-page-name "physics.org"
  "File name of the literate page; `luv-physics-mode' starts in such files beside luv-physics.asd."
  :type 'string)

(defvar luv-physics-mode-map
  (let ((map (make-sparse-keymap)))
    (define-key map (kbd "C-c M-.") #'luv-physics-definitions)
    (define-key map (kbd "C-c M-g") #'luv-physics-page-definition)
    (define-key map (kbd "C-c M-s") #'luv-physics-section)
    (define-key map (kbd "C-c M-r") #'luv-physics-reload-section)
    (define-key map (kbd "C-c M-u") #'luv-physics-reload-changed)
    map)
  "Keys of `luv-physics-mode'.")

;;;###autoload
(define-minor-mode luv-physics-mode
  "Jump between physics.org and a running luv-physics image, and reload sections into it.
\\{luv-physics-mode-map}"
  :lighter " Luv"
  :keymap luv-physics-mode-map
  (if luv-physics-mode
      (progn
        (add-hook 'org-ctrl-c-ctrl-c-hook #'luv-physics-ctrl-c-ctrl-c nil t)
        ;; a block's text is the tangled text (tools/tangle.el tangles so): C-c ' and back
        ;; must give the block back byte for byte, not indented by Org's two spaces
        (setq-local org-src-preserve-indentation t)
        (setq-local org-edit-src-content-indentation 0))
    (remove-hook 'org-ctrl-c-ctrl-c-hook #'luv-physics-ctrl-c-ctrl-c t)
    (kill-local-variable 'org-src-preserve-indentation)
    (kill-local-variable 'org-edit-src-content-indentation)))

(defun luv-physics-page-p ()
  "True in a buffer visiting the page: physics.org beside luv-physics.asd."
  (and buffer-file-name
       (string= (file-name-nondirectory buffer-file-name) luv-physics-page-name)
       (file-exists-p (expand-file-name "luv-physics.asd" (file-name-directory buffer-file-name)))))

(defun luv-physics-maybe-enable ()
  "Turn on `luv-physics-mode' in the page."
  (when (luv-physics-page-p) (luv-physics-mode 1)))

(add-hook 'org-mode-hook #'luv-physics-maybe-enable)

;;; Talking to the image

(defun luv-physics-connected-p ()
  "True when SLIME is loaded and connected."
  (and (featurep 'slime) (fboundp 'slime-connected-p) (slime-connected-p)))

(defun luv-physics-eval (function &rest arguments)
  "Call FUNCTION, a symbol name of the package LUV-PHYSICS, on ARGUMENTS in the image."
  (slime-eval `(cl:funcall (cl:find-symbol ,(upcase function) "LUV-PHYSICS") ,@arguments)
              "COMMON-LISP-USER"))

(defun luv-physics-image-ready-p ()
  "True when SLIME is connected to an image that has loaded luv-physics/workshop: the engine
alone has no answers for the editor."
  (and (luv-physics-connected-p)
       (slime-eval '(cl:and (cl:find-package "LUV-PHYSICS")
                            (cl:fboundp (cl:find-symbol "EDITOR-SECTION" "LUV-PHYSICS"))
                            cl:t)
                   "COMMON-LISP-USER")))

(defun luv-physics-require-image ()
  "Signal a user error unless an image with luv-physics/workshop is connected."
  (unless (luv-physics-image-ready-p)
    (user-error "luv-physics: this needs SLIME connected to an image that loaded luv-physics/workshop \
\(M-x slime, then (load \"tools/boot.lisp\") (asdf:load-system \"luv-physics/workshop\"))")))

(defun luv-physics-page-buffer ()
  "The buffer of the page: this one, or the one an edit buffer came from."
  (cond ((luv-physics-page-p) (current-buffer))
        ((and (fboundp 'org-src-edit-buffer-p) (org-src-edit-buffer-p))
         (org-src-source-buffer))
        (t nil)))

(defun luv-physics-page-file ()
  "The file name of the page at hand, or of the image's page."
  (let ((buffer (luv-physics-page-buffer)))
    (or (and buffer (buffer-file-name buffer))
        (and (luv-physics-image-ready-p)
             (luv-physics-eval "editor-page")))))

;;; Where we are on the page

(defun luv-physics-anchor-at-point ()
  "The anchor of the [[#ANCHOR]] link at point, or of the section point is in."
  (let ((context (ignore-errors (org-element-context))))
    (if (and (eq 'link (car-safe context))
             (equal "custom-id" (org-element-property :type context)))
        (org-element-property :path context)
      (save-excursion
        (unless (org-before-first-heading-p)
          (org-back-to-heading t)
          (or (org-entry-get nil "CUSTOM_ID")
              (user-error "luv-physics: this heading has no CUSTOM_ID")))))))

(defun luv-physics-goto-line (file line)
  "Visit FILE at LINE, showing the line however the page is folded."
  (let ((buffer (find-file-noselect file)))
    (switch-to-buffer buffer)
    (widen)
    (goto-char (point-min))
    (forward-line (1- line))
    (when (derived-mode-p 'org-mode) (org-show-context 'link-search))
    (back-to-indentation)
    (point)))

(defun luv-physics-text-definitions (anchor)
  "Without an image: each (LABEL LINE) for the lines of section ANCHOR that start a definition."
  (save-excursion
    (save-restriction
      (widen)
      (goto-char (point-min))
      (unless (re-search-forward (format "^[ \t]*:CUSTOM_ID:[ \t]*%s[ \t]*$" (regexp-quote anchor)) nil t)
        (user-error "luv-physics: no section %s on this page" anchor))
      (let ((end (save-excursion (or (outline-next-heading) (point-max))))
            (found '()))
        (while (re-search-forward "^(\\(def[^ \t\n]*\\)[ \t]+(?\\([^ \t\n()]+\\)" end t)
          (push (list (format "%-36s %-16s %6d" (match-string-no-properties 2)
                              (match-string-no-properties 1) (line-number-at-pos))
                      (line-number-at-pos))
                found))
        (nreverse found)))))

;;; Anchor -> definitions

(defun luv-physics-visit-definition (anchor name &optional tangled)
  "Visit definition NAME (a string, as the image prints it) of section ANCHOR: its line on the
page, or with TANGLED its line in the tangled file.  Return the line."
  (let* ((page (luv-physics-page-file))
         (records (luv-physics-eval "editor-definitions" anchor))
         (record (or (assoc name records)
                     (user-error "luv-physics: section %s defines no %s" anchor name))))
    (if tangled
        (luv-physics-goto-line (expand-file-name (nth 3 record) (file-name-directory page)) (nth 4 record))
      (luv-physics-goto-line page (nth 2 record)))
    (line-number-at-pos)))

(defun luv-physics-definitions (tangled)
  "Choose a definition of the section at point, or of the link at point, and visit its line on
the page; with a prefix argument TANGLED, in the tangled file."
  (interactive "P")
  (let ((anchor (luv-physics-anchor-at-point)))
    (if (luv-physics-image-ready-p)
        (let* ((records (luv-physics-eval "editor-definitions" anchor))
               (labels (mapcar (lambda (r) (cons (format "%-36s %-16s %6s" (nth 0 r) (nth 1 r) (nth 2 r))
                                                 (nth 0 r)))
                               records)))
          (unless records (user-error "luv-physics: the image knows no definitions of %s" anchor))
          (let ((choice (completing-read (format "Definition of %s: " anchor) labels nil t)))
            (luv-physics-visit-definition anchor (cdr (assoc choice labels)) tangled)))
      (when tangled
        (user-error "luv-physics: the tangled file's lines come from the image; connect SLIME"))
      (let* ((found (luv-physics-text-definitions anchor))
             (choice (completing-read (format "Definition of %s (page text): " anchor) found nil t)))
        (luv-physics-goto-line buffer-file-name (cadr (assoc choice found)))))))

;;; Symbol -> page

(defun luv-physics-symbol-at-point ()
  "The symbol at point, as a string."
  (or (if (fboundp 'slime-symbol-at-point) (slime-symbol-at-point) (thing-at-point 'symbol t))
      (user-error "luv-physics: no symbol at point")))

(defun luv-physics-buffer-package ()
  "The Lisp package of this buffer, as SLIME sees it, or COMMON-LISP-USER."
  (or (and (fboundp 'slime-current-package) (ignore-errors (slime-current-package)))
      "COMMON-LISP-USER"))

(defun luv-physics-page-definition (name)
  "Visit the line of the page where the definition of NAME (the symbol at point) starts."
  (interactive (list (luv-physics-symbol-at-point)))
  (if (luv-physics-image-ready-p)
      (let ((where (luv-physics-eval "editor-page-line" name (luv-physics-buffer-package))))
        (unless where (user-error "luv-physics: the page defines no %s" name))
        (push-mark nil t)
        (luv-physics-goto-line (nth 2 where) (nth 1 where))
        (message "%s: section %s, line %d" name (nth 0 where) (nth 1 where))
        (nth 1 where))
    (let ((page (or (and (luv-physics-page-buffer) (buffer-file-name (luv-physics-page-buffer)))
                    (user-error "luv-physics: no page at hand and no image to ask"))))
      (let ((line (with-current-buffer (find-file-noselect page)
                    (save-excursion
                      (save-restriction
                        (widen)
                        (goto-char (point-min))
                        (and (re-search-forward (format "^[ \t]*(def[^ \t\n]*[ \t]+(?%s[ \t\n)]"
                                                        (regexp-quote (car (last (split-string name ":")))))
                                                nil t)
                             (line-number-at-pos (match-beginning 0))))))))
        (unless line (user-error "luv-physics: the page defines no %s" name))
        (push-mark nil t)
        (luv-physics-goto-line page line)))))

;;; Sections and reloading

(defun luv-physics-section ()
  "Show what the image knows of the section at point: definitions with lines, claims."
  (interactive)
  (luv-physics-require-image)
  (let ((text (luv-physics-eval "editor-section" (luv-physics-anchor-at-point) (luv-physics-page-file)))
        ;; selected, the window takes the q its message asks for, which would otherwise land in the page
        (help-window-select t))
    (with-help-window "*luv-physics section*" (princ text))))

(defun luv-physics-save-page ()
  "Save the page, as the image reads it from its file."
  (let ((buffer (luv-physics-page-buffer)))
    (when (and buffer (buffer-modified-p buffer))
      (with-current-buffer buffer (save-buffer)))))

(defun luv-physics-reload-section (block-only)
  "Save the page and reload the section at point into the image; with a prefix argument
BLOCK-ONLY, only the block at point.  Show the image's one-line summary and return it."
  (interactive "P")
  (luv-physics-require-image)
  (luv-physics-save-page)
  (let* ((anchor (luv-physics-anchor-at-point))
         (summary (luv-physics-eval "reload-section" anchor
                                    :page (luv-physics-page-file)
                                    :line (and block-only (line-number-at-pos)))))
    (message "%s" summary)
    summary))

(defun luv-physics-ctrl-c-ctrl-c ()
  "On a Lisp block of the page, reload that block (for `org-ctrl-c-ctrl-c-hook')."
  (let ((element (org-element-at-point)))
    (when (and (eq 'src-block (org-element-type element))
               (equal "lisp" (org-element-property :language element))
               ;; a claim's block belongs to the tests, not to the engine
               (not (string-match-p ":tangle[ \t]+tests/"
                                    (or (org-element-property :parameters element) "")))
               (luv-physics-image-ready-p))
      (luv-physics-reload-section t)
      t)))

(defun luv-physics-tangled-files (page)
  "The files PAGE, a file name, tangles into: the targets of its :tangle header arguments."
  (let ((directory (file-name-directory page)) (files '()))
    (with-current-buffer (find-file-noselect page)
      (save-excursion
        (save-restriction
          (widen)
          (goto-char (point-min))
          (while (re-search-forward "^[ \t]*\\(?:#\\+begin_src\\|#\\+property:\\|:header-args\\)[^\n]*:tangle[ \t]+\\([^ \t\n]+\\)" nil t)
            (let ((target (match-string-no-properties 1)))
              (unless (member target '("no" "yes"))
                (cl-pushnew (expand-file-name target directory) files :test #'string=)))))))
    (nreverse files)))

(defun luv-physics-revert-tangled (page)
  "Revert, without asking, each unmodified buffer visiting a file PAGE tangles into that changed
on disk; return those buffers."
  (let ((files (luv-physics-tangled-files page)) (reverted '()))
    (dolist (buffer (buffer-list))
      (let ((file (buffer-file-name buffer)))
        (when (and file (member (expand-file-name file) files)
                   (file-exists-p file)
                   (not (buffer-modified-p buffer))
                   (not (verify-visited-file-modtime buffer)))
          (with-current-buffer buffer
            (let ((inhibit-message t)) (revert-buffer t t t)))
          (push buffer reverted))))
    reverted))

(defun luv-physics-reload-changed ()
  "Save the page, tangle it in the image's process and reload every form whose text changed; the
buffers visiting the tangled files are reverted, without a question, to the new text."
  (interactive)
  (luv-physics-require-image)
  (luv-physics-save-page)
  (let* ((page (luv-physics-page-file))
         (summary (luv-physics-eval "reload-changed" :page page)))
    (luv-physics-revert-tangled page)
    (message "%s" summary)
    summary))

;;; Edit buffers, the REPL and Lisp buffers

(defun luv-physics-src-package ()
  "In a `C-c '' edit buffer of the page, take the package of the block's tangled file."
  (let ((source (and (fboundp 'org-src-source-buffer) (ignore-errors (org-src-source-buffer)))))
    (when (and source (buffer-local-value 'luv-physics-mode source)
               (memq major-mode '(lisp-mode common-lisp-mode)))
      (let* ((begin (marker-position org-src--beg-marker))
             (header (with-current-buffer source
                      (save-excursion
                        (goto-char begin)
                        (org-element-property :parameters (org-element-at-point))))))
        (setq-local slime-buffer-package
                    (if (and header (string-match-p ":tangle[ \t]+tests/" header))
                        "LUV-PHYSICS-TESTS"
                      "LUV-PHYSICS"))
        (local-set-key (kbd "C-c M-g") #'luv-physics-page-definition)))))

(add-hook 'org-src-mode-hook #'luv-physics-src-package)

(defun luv-physics-slime-keys ()
  "Bind the symbol -> page jump in SLIME's Lisp buffers and REPL."
  (when (boundp 'slime-mode-map)
    (define-key slime-mode-map (kbd "C-c M-g") #'luv-physics-page-definition))
  (when (boundp 'slime-repl-mode-map)
    (define-key slime-repl-mode-map (kbd "C-c M-g") #'luv-physics-page-definition)))

(defun luv-physics-on-connect ()
  "When SLIME connects, let an image that has loaded luv-physics show its objects in the inspector."
  (ignore-errors
    (slime-eval '(cl:let ((f (cl:and (cl:find-package "LUV-PHYSICS")
                                     (cl:find-symbol "INSTALL-SWANK-INSPECTION" "LUV-PHYSICS"))))
                  (cl:when (cl:and f (cl:fboundp f)) (cl:funcall f)))
                "COMMON-LISP-USER")))

(with-eval-after-load 'slime
  (luv-physics-slime-keys)
  (add-hook 'slime-connected-hook #'luv-physics-on-connect))
(with-eval-after-load 'slime-repl (luv-physics-slime-keys))

(provide 'luv-physics)

;;; luv-physics.el ends here
